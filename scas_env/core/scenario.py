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

from dataclasses import dataclass, fields

from scas_env.actuator.config import Validated, param

FIDELITIES = ("surrogate", "physics")
OBS_MODES = ("features+rul", "features", "state", "dict")
INITIAL_HEALTH = ("new", "random", "in_service")
PREFLIGHT = ("on_demand", "every_flight")
REJUVENATION = ("none", "resample_move", "resample_move_both")


@dataclass(frozen=True)
class Scenario(Validated):
    """Everything about an episode that is not the actuator design or the costs.

    Attributes
    ----------
    fidelity : ``"surrogate"`` (features drawn from a model calibrated on physics
        campaigns; microseconds per step) or ``"physics"`` (the actuator is simulated for
        every pre-flight test and flight window). Both grow the parts with the same
        calibrated whole-flight growth and each part's own growth draws.
    obs_mode : ``"features+rul"``, ``"features"`` (no filter entries; the filters still
        correct the alarms' readings), ``"state"`` (true severities and lives: the oracle's
        view) or ``"dict"`` (every quantity, for inspection).
    initial_health : ``"new"`` (new parts at reset), ``"random"`` (each part starts at a
        uniformly drawn fraction of its life, its age unknown to the monitor) or
        ``"in_service"`` (each part has flown a uniformly drawn fraction of its own life,
        grown by its own draws; the operator knows its age, and the monitor's filters start
        from the new-part prior predicted over those flights and conditioned on the part
        having survived them: a fleet in service with its maintenance records).
    preflight : ``"on_demand"`` (the test runs when action 1 asks for it and costs
        ``test_usd``) or ``"every_flight"`` (the paper's concept: the test runs at every
        power-up, before every flight, at no cost; action 1 then equals action 0).
    rejuvenation : how the filters keep their hold on their static parameters (the spring's
        initial crack depth and log growth multiplier; the seal's log wear multiplier) when
        they resample. ``"none"`` (the default): the
        regularised particle filter's kernel jitter (Liu & West 2001 shrinkage).
        ``"resample_move"``: resample-move (Gilks & Berzuini 2001): the spring filter's
        process is the noise-free damage integral of its growth table (the whole-flight
        scatter, which moves a life by about 0.1 %, left out, as the reference posterior
        leaves it out), every datum it learns is kept per row, and after each resampling
        every particle takes ``rejuvenation_steps`` random-walk Metropolis-Hastings steps
        whose target is the full-history posterior (prior x every likelihood term, the
        installation effects integrated out, survival), so the cloud stays a sample of the
        exact posterior of the filter's model (docs/beliefs.md). Needs a spring of known age
        (``initial_health`` ``"new"`` or ``"in_service"``) and ``spring_theta_walk`` = 0.
        The seal filter is unchanged. ``"resample_move_both"``: the spring's as
        ``"resample_move"`` and the seal filter's too: its process is the filter's linear
        Archard wear without the whole-flight scatter (a new seal's wear is ``rate theta
        t``), every datum it learns (I9 batch means, G3) is kept, with the installation
        effects' beliefs at the seal's fitting and their reset to N(0, 1) where a new
        spring pair is fitted during the seal's life, and after each resampling its log
        theta takes ``rejuvenation_steps`` 1-D random-walk Metropolis-Hastings steps (sd
        2.38 times the weighted cloud's) on the seal's full-history posterior. Needs
        ``wear_active`` = 1 as well.
    """

    fidelity: str = "surrogate"
    obs_mode: str = "features+rul"
    initial_health: str = "new"
    preflight: str = "on_demand"
    rejuvenation: str = "none"
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
        lo=0.01,
        hi=100.0,
        source="multiplies the measurement noise the filters assume (filter-quality studies; "
        "far below 0.01 the filters' likelihoods underflow and an episode stops mid-way)",
    )
    filter_growth_bias: float = param(
        1.0,
        "-",
        lo=0.01,
        hi=100.0,
        source="multiplies the growth rates the filters assume (a model that is off; far "
        "below 0.01 the filters' growth tables underflow)",
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
        source="flights per update of the filters by the in-flight features I8, I9: the "
        "ground station processes the flight-data downloads in batches",
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
        source="random walk of the spring filter's log theta (std per sqrt(flight); 0: none, "
        "the growth multiplier is static; docs/beliefs.md)",
    )
    cross_variance_inflation: float = param(
        1.0,
        "-",
        lo=1.0,
        hi=1000.0,
        source="factor on the variance the other part's estimate adds to each feature's "
        "likelihood in the monitor's filters (the seal's: seal_cross_variance_inflation "
        "unless 0); 1: that estimate's error independent from datum "
        "to datum; (1 + rho) / (1 - rho) for an error correlated rho between consecutive data "
        "(docs/beliefs.md)",
    )
    seal_cross_variance_inflation: float = param(
        0.0,
        "-",
        lo=0.0,
        hi=1000.0,
        source="the seal filter's own cross_variance_inflation (the factor on the variance the "
        "spring's estimate adds to I9's and G3's likelihoods), 1-1000; 0: the same as "
        "cross_variance_inflation (docs/beliefs.md)",
    )
    seal_cross_persistence: float = param(
        0.0,
        "-",
        lo=0.0,
        hi=0.9999,
        source="per-flight AR(1) correlation of the spring estimate's error as the seal filter "
        "carries it: each seal particle reads G3 and I9 at its own spring value, the estimate "
        "plus that error (its variance not added, seal_cross_variance_inflation unused); 0: "
        "off (the variance factor)",
    )
    rejuvenation_steps: float = param(
        1,
        "MH steps",
        lo=1,
        hi=100,
        integer=True,
        source="Metropolis-Hastings steps per particle after each resampling of a moved "
        "filter: the spring's with rejuvenation 'resample_move', both with "
        "'resample_move_both' (Gilks & Berzuini 2001; docs/beliefs.md)",
    )

    def _check(self) -> None:
        for name, allowed in (
            ("fidelity", FIDELITIES),
            ("obs_mode", OBS_MODES),
            ("initial_health", INITIAL_HEALTH),
            ("preflight", PREFLIGHT),
            ("rejuvenation", REJUVENATION),
        ):
            value = getattr(self, name)
            if value not in allowed:
                raise ValueError(f"Scenario.{name} = {value!r} must be one of {allowed}")
        if 0.0 < self.seal_cross_variance_inflation < 1.0:
            raise ValueError(
                "Scenario.seal_cross_variance_inflation = "
                f"{self.seal_cross_variance_inflation!r} must be 0 (the same as "
                "cross_variance_inflation) or in [1, 1000]"
            )
        if self.seal_cross_persistence > 0 and self.rejuvenation == "resample_move_both":
            raise ValueError(
                f"Scenario.seal_cross_persistence = {self.seal_cross_persistence!r} needs the "
                "seal filter without resample-move (rejuvenation 'none' or 'resample_move')"
            )
        if not (self.crack_active or self.wear_active):
            raise ValueError("Scenario: at least one of crack_active, wear_active must be 1")
        defaults = {f.name: f.default for f in fields(self)}
        for name, unread, why in (  # a field the other settings leave unread: not set
            ("window_library", self.fidelity == "surrogate", "the physics fidelity's"),
            ("rejuvenation_steps", self.rejuvenation == "none", "a moved filter's"),
            (
                "seal_cross_variance_inflation",
                self.seal_cross_persistence > 0,
                "unused with seal_cross_persistence > 0 (the spring's error carried, not its "
                "variance); the factor",
            ),
        ):
            if unread and getattr(self, name) != defaults[name]:
                raise ValueError(
                    f"Scenario.{name} = {getattr(self, name)!r} has no effect here: it is "
                    f"{why} setting (fidelity {self.fidelity!r}, rejuvenation "
                    f"{self.rejuvenation!r}, seal_cross_persistence "
                    f"{self.seal_cross_persistence!r}); leave it at {defaults[name]!r}"
                )
        if self.rejuvenation != "none":
            r = self.rejuvenation
            if self.initial_health == "random":
                raise ValueError(
                    f"Scenario.rejuvenation = {r!r} needs each part's age known to "
                    "the monitor (initial_health 'new' or 'in_service'), got initial_health = "
                    "'random'"
                )
            if self.spring_theta_walk != 0.0:
                raise ValueError(
                    f"Scenario.rejuvenation = {r!r} moves a static growth multiplier: "
                    f"spring_theta_walk must be 0, got {self.spring_theta_walk}"
                )
            if not self.crack_active:
                raise ValueError(
                    f"Scenario.rejuvenation = {r!r} moves the spring crack's "
                    "parameters: crack_active must be 1, got crack_active = 0"
                )
            if r == "resample_move_both" and not self.wear_active:
                raise ValueError(
                    f"Scenario.rejuvenation = {r!r} moves the seal wear's "
                    "parameter: wear_active must be 1, got wear_active = 0"
                )


__all__ = ["FIDELITIES", "INITIAL_HEALTH", "OBS_MODES", "PREFLIGHT", "REJUVENATION", "Scenario"]
