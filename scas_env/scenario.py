"""Scenario of a maintenance episode: fidelity, observation, horizon, filters, active faults.

Files: ``Scenario.load("case.toml")`` / ``scenario.save("s.yaml")`` (TOML, YAML or JSON; the
fields at the top level or in a ``[scenario]`` table; docs/configs.md).

>>> s = Scenario()
>>> s.fidelity, s.obs_mode, s.episode_slots
('surrogate', 'features+rul', 2000)
>>> Scenario(fidelity="fast")
Traceback (most recent call last):
...
ValueError: Scenario.fidelity = 'fast' must be one of ('surrogate', 'physics')
"""

from __future__ import annotations

from dataclasses import dataclass

from scas_env.actuator.config import Validated, param

FIDELITIES = ("surrogate", "physics")
OBS_MODES = ("features+rul", "features", "state", "dict")
INITIAL_HEALTH = ("new", "random")
GO_NO_GO = ("detection_band", "airworthiness")
PREFLIGHT = ("on_demand", "every_flight")
#: In-flight features the world measures and the observation shows (comma-separated, in
#: observation order): Table 2's selected three, or those plus I8 and I9
#: (prognostics.features, docs/prognostics.md "In-flight features").
FLIGHT_FEATURE_SETS = ("I2,I6,I7", "I2,I6,I7,I8,I9")
DEGRADATION_DRAWS = ("per_slot", "per_part")
DAMAGE_SCATTER = ("window", "whole_flight")


@dataclass(frozen=True)
class Scenario(Validated):
    """Everything about an episode that is not the actuator design or the costs.

    Attributes
    ----------
    fidelity : ``"surrogate"`` (features from a model calibrated on physics campaigns,
        degradation from the calibrated growth tables; microseconds per step) or
        ``"physics"`` (the actuator is simulated for every test and flight window).
    obs_mode : ``"features+rul"``, ``"features"`` (no particle filter), ``"state"`` (true
        severities: the oracle's view) or ``"dict"`` (every quantity, for inspection).
    initial_health : ``"new"`` (new parts at reset) or ``"random"`` (each part starts at a
        uniformly drawn fraction of its life, as on a fleet in service).
    go_no_go : what a failed pre-flight test means (:mod:`scas_env.acceptance`):
        ``"detection_band"`` (v0: outside the healthy population's band) or
        ``"airworthiness"`` (v1: a ground feature moved from the installation's reference as
        far as a part at its critical level; the aircraft then stays on the ground until a
        passing re-test or a replacement clears it).
    preflight : ``"on_demand"`` (the test runs when action 1 asks for it and costs
        ``test_usd``) or ``"every_flight"`` (the paper's concept: the test runs at every
        power-up, before every flight, at no cost; action 1 then equals action 0).
    flight_features : in-flight features measured every flight, one of
        ``FLIGHT_FEATURE_SETS``: ``"I2,I6,I7"`` (v0, v1: the paper's selection, none of which
        sees the crack) or ``"I2,I6,I7,I8,I9"`` (v2: plus the DC current offset I8, which sees
        the crack, and the command-normalised current I9, which sees seal wear; the filters
        then learn from them every ``flight_update_flights`` flights).
    degradation_draws : where each flight's growth factors come from (surrogate fidelity).
        ``"per_slot"`` (v0, v1): one stream hands each flown slot its two factors, and one
        parts stream hands the k-th replacement of either part its new part, so a policy that
        flies or replaces at other times flies other lives. ``"per_part"`` (v2): each part
        carries its own stream of growth factors, and springs and seals come from their own
        parts streams, so the k-th spring (seal) fitted in an episode is the same part with
        the same life whatever the policy did: common random numbers per part, and a
        clairvoyant oracle can know every life (``ScasMaintenanceEnv.part_lives``).
    damage_scatter : flight-to-flight scatter of the growth (surrogate fidelity), from the
        calibration: ``"window"`` (v0, v1: one 20 s window's damage scaled to the 1.5 h
        flight, CV 8-26 % for the crack, an artefact of scaling ~1.3 cycles of the damaging
        regime) or ``"whole_flight"`` (v2: whole simulated flights, CV 0.6-1.9 %;
        docs/physics.md). The world grows the parts and the filters model the growth with it.
    spring_effect_realign : after each resampling of the spring filter, re-condition each
        jittered particle's installation-effect states on its new crack depth (the data's
        information on them carried along a parallel shift of its path,
        ``scas_env.learning_kernel.realign_effect``; docs/beliefs.md, "Spring calibration";
        default False: the v2 filter; measured not to help). Needs the filters learning in
        flight (``flight_features`` with I8 and I9).
    """

    fidelity: str = "surrogate"
    obs_mode: str = "features+rul"
    initial_health: str = "new"
    go_no_go: str = "detection_band"
    preflight: str = "on_demand"
    flight_features: str = "I2,I6,I7"
    degradation_draws: str = "per_slot"
    damage_scatter: str = "window"
    episode_slots: float = param(
        2000,
        "slots",
        lo=1,
        hi=10_000_000,
        integer=True,
        source="about 1.7 spring and seal lives without maintenance (docs/physics.md, calibration)",
    )
    n_particles: float = param(
        200, "-", lo=10, hi=100_000, integer=True, source="particles per filter (per part)"
    )
    risk_horizon_flights: float = param(
        20,
        "flights",
        lo=1,
        hi=10_000,
        integer=True,
        source="horizon of the probability-of-failure observation [B] (ref §9: 10 flights)",
    )
    rul_quantile: float = param(
        0.05, "-", lo=0.0, hi=0.5, lo_open=True, source="low quantile of the RUL observation"
    )
    rul_cap_flights: float = param(
        5000,
        "flights",
        lo=1,
        hi=1e7,
        source="RUL observations saturate here (documented bound of the observation)",
    )
    crack_active: float = param(1, "bool", lo=0, hi=1, integer=True, source="spring crack on")
    wear_active: float = param(1, "bool", lo=0, hi=1, integer=True, source="seal wear on")
    go_no_go_false_alarm: float = param(
        0.001,
        "-",
        lo=1e-9,
        hi=0.5,
        source="probability that a healthy actuator fails the pre-flight test (sets the band)",
    )
    detection_window: float = param(
        20,
        "samples",
        lo=2,
        hi=1000,
        integer=True,
        source="running window of the section-5.1 detector ([DJS20] rule, ref §9)",
    )
    filter_noise_scale: float = param(
        1.0,
        "-",
        lo=0.0,
        lo_open=True,
        hi=100.0,
        source="multiplies the measurement noise the filters assume (filter-quality studies)",
    )
    filter_growth_bias: float = param(
        1.0,
        "-",
        lo=0.0,
        lo_open=True,
        hi=100.0,
        source="multiplies the growth rates the filters assume (a model that is off)",
    )

    reference_tests: float = param(
        4,
        "tests",
        lo=1,
        hi=100,
        integer=True,
        source="airworthiness go/no-go: tests averaged into the installation's reference at "
        "fitting (a fitting check of a few power-ups)",
    )
    acceptance_catch: float = param(
        0.9,
        "-",
        lo=0.5,
        hi=0.999,
        source="airworthiness go/no-go: probability that a part at its critical level fails "
        "the test (the limit sits at that quantile of its reading)",
    )
    flight_update_flights: float = param(
        10,
        "flights",
        lo=1,
        hi=1000,
        integer=True,
        source="filters fed by in-flight features (flight_features with I8, I9): flights per "
        "update, the ground station processing the flight-data downloads in batches",
    )
    window_library: float = param(
        64,
        "windows",
        lo=0,
        hi=100_000,
        integer=True,
        source="physics fidelity: each flight flies one of this many Table-1 windows drawn at "
        "reset, each window's healthy baseline simulated once (0: a new window every flight)",
    )
    spring_theta_walk: float = param(
        0.0,
        "1/sqrt(flight)",
        lo=0.0,
        hi=0.05,
        source="random walk of the spring filter's log theta (std per sqrt(flight)) when the "
        "filters learn in flight (flight_features with I8, I9; 0: none, the v2 filter; "
        "docs/beliefs.md, 'Spring calibration'). v0/v1 keep their own fixed walk",
    )
    spring_effect_realign: bool = False

    def _check(self) -> None:
        for name, allowed in (
            ("fidelity", FIDELITIES),
            ("obs_mode", OBS_MODES),
            ("initial_health", INITIAL_HEALTH),
            ("go_no_go", GO_NO_GO),
            ("preflight", PREFLIGHT),
            ("flight_features", FLIGHT_FEATURE_SETS),
            ("degradation_draws", DEGRADATION_DRAWS),
            ("damage_scatter", DAMAGE_SCATTER),
        ):
            value = getattr(self, name)
            if value not in allowed:
                raise ValueError(f"Scenario.{name} = {value!r} must be one of {allowed}")
        if not isinstance(self.spring_effect_realign, bool):
            raise ValueError(
                f"Scenario.spring_effect_realign = {self.spring_effect_realign!r} must be "
                "true or false"
            )
        learning = {"I8", "I9"} & set(self.flight_feature_names)
        for name in ("spring_theta_walk", "spring_effect_realign"):
            value = getattr(self, name)
            if value and not learning:
                raise ValueError(
                    f"Scenario.{name} = {value!r} needs the filters learning in flight: "
                    f"flight_features 'I2,I6,I7,I8,I9', not {self.flight_features!r}"
                )
        if not (self.crack_active or self.wear_active):
            raise ValueError("Scenario: at least one of crack_active, wear_active must be 1")
        if self.degradation_draws == "per_part" and self.fidelity == "physics":
            raise ValueError(
                "Scenario.degradation_draws = 'per_part' needs fidelity 'surrogate' (the "
                "physics takes each flight's damage from its simulated window)"
            )

    @property
    def flight_feature_names(self) -> tuple[str, ...]:
        """The in-flight features measured every flight, in observation order."""
        return tuple(self.flight_features.split(","))
