"""The simulated actuator across flights: hidden state, degradation, measurements, failures.

One :class:`ActuatorWorld` is one SCAS actuator in service. It knows the truth (crack
depth, seal wear, the unit's growth constants) and answers three requests:

* :meth:`ActuatorWorld.test`: run the pre-flight test, return G1 and G3;
* :meth:`ActuatorWorld.fly`: fly one flight: in-flight features (I2, I6, I7) measured on the
  way, damage added, and which parts failed (their critical value reached during the
  flight: an in-flight failure; the flight is aborted and its features are not reported);
* :meth:`ActuatorWorld.replace`: fit a new spring pair or a new seal set.

Two fidelities, one interface:

* ``"surrogate"``: features from :class:`~scas_env.actuator.surrogate.SurrogateModel`
  (installation effects drawn when a spring pair is fitted); damage from the calibrated
  growth tables: the crack advances by the damage integral of the table times the unit's
  multiplier ``theta = C_unit / C_nom`` times a lognormal flight factor of the calibrated
  flight-to-flight scatter, the wear by ``r k_w,unit / k_w,nom`` times its own factor.
* ``"physics"``: the actuator is simulated for each test and each flight window
  (:mod:`scas_env.actuator.sensing`); the crack grows by Paris' law on the window's rainflow
  cycles scaled to the flight, the wear by Archard on its friction work
  (:mod:`scas_env.actuator.flight_damage`).

Degradation draws (``Scenario.degradation_draws``): ``"per_slot"`` takes each flight's two
growth factors from the ``degradation_rng`` given to :meth:`ActuatorWorld.fly`;
``"per_part"`` gives each fitted part its own stream of factors (a
:class:`~scas_env.block_draws.NormalBuffer` seeded from the part's parts stream when it is
fitted), so a part's whole life is fixed when it is fitted: :attr:`ActuatorWorld.life_left`
holds what is left of it (flights up to and including the failing one), computed at fitting
by replaying the part's own draws with the flight's arithmetic (:mod:`scas_env.fleet_kernels`)
and counted down by every flight, an aborted one included (its growth happened).

The spring failure depth is the nominal one (calibration) in the surrogate and the unit's
own (its wire and coil diameters) in the physics; the seal fails at the calibrated
critical wear in both. Everything random comes from the ``rng`` passed to each call.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace

import numpy as np

from prognostics.degradation_models import TabulatedRateModel, paris_crack_model
from scas_env.actuator.calibration import Calibration
from scas_env.actuator.flight_damage import (
    crack_increment_m,
    flight_loads_from_run,
    growth_model,
    wear_increment_m,
)
from scas_env.actuator.health import CRACKED_SPRING, HealthState, actuator_config
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.spring import failure_depth_from_params
from scas_env.actuator.sensing import FlightWindow, draw_window, flight_window, ground_test
from scas_env.actuator.surrogate import SurrogateModel
from scas_env.actuator.uncertainty import UnitSample, draw_run_conditions, draw_unit
from scas_env.block_draws import NormalBuffer
from scas_env.fleet_kernels import (
    crack_flights_to_failure,
    surrogate_flights,
    true_rul,
    wear_flights_to_failure,
)
from scas_env.fleet_state import PARTS
from scas_env.scenario import Scenario

GROUND_FEATURES = ("G1", "G3")
#: The in-flight features of the default scenario (v0, v1); ``Scenario.flight_features``
#: chooses the set a world measures (:attr:`ActuatorWorld.flight_features`).
FLIGHT_FEATURES = ("I2", "I6", "I7")


@dataclass(frozen=True)
class FlightResult:
    """Outcome of one flight.

    Attributes
    ----------
    features : in-flight features (NaN when the flight was aborted by a failure).
    failed : parts that reached their critical value during the flight.
    """

    features: dict[str, float]
    failed: tuple[str, ...]


class ActuatorWorld:
    """One actuator in service (see the module docstring)."""

    def __init__(
        self,
        params: ScasParams,
        scenario: Scenario,
        calibration: Calibration,
        surrogate: SurrogateModel,
    ) -> None:
        self.params = params
        self.scenario = scenario
        self.calibration = calibration
        self.surrogate = surrogate
        self._table = paris_crack_model(
            calibration.crack_depth_m, calibration.crack_rate_m_per_flight
        )
        #: in-flight features measured every flight (``Scenario.flight_features``)
        self.flight_features = scenario.flight_feature_names
        self._flight_feature_idx = [surrogate.index(f) for f in self.flight_features]
        self._ground_feature_idx = [surrogate.index(f) for f in GROUND_FEATURES]
        # installation effects are drawn for the surrogate's features up to the last one this
        # world measures (v0 and v1 draw the five they drew before I8 and I9 existed)
        self._unit_z_draws = 1 + max(self._flight_feature_idx + self._ground_feature_idx)
        self.unit: UnitSample | None = None
        self.crack_m = 0.0
        self.wear_m = 0.0
        self.spring_failure_m = calibration.spring_failure_depth_m
        self.unit_z = np.zeros(len(surrogate.features))
        self.kernel_tables = kernel_tables(calibration, surrogate, scenario, self._table)
        self._wear_cv = calibration.flight_scatter(scenario.damage_scatter)[1]
        self.per_part = scenario.degradation_draws == "per_part"
        #: per-part growth factor streams (``"per_part"``), and the storage rows a vector
        #: env lends them (name -> (values, position), as ``ScasMaintenanceEnv.buffer_storage``)
        self.growth: dict[str, NormalBuffer] = {}
        self.buffer_storage: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        #: ``"per_part"``: flights each fitted part will still fly, the failing one included
        self.life_left = {"spring": math.inf, "seal": math.inf}
        #: ``"per_part"``: whole lives of the next :data:`UPCOMING_PARTS` parts of each kind
        #: (the clairvoyant oracle's view; refreshed when a part of that kind is fitted, in
        #: the observation modes that show them, ``"state"`` and ``"dict"``; else inf: the
        #: look-ahead replays three lives per replacement and moves no draw)
        self.upcoming = {part: [math.inf] * UPCOMING_PARTS for part in PARTS}
        self._look_ahead = scenario.obs_mode in ("state", "dict")
        self._scratch = {
            "envs": np.zeros(1, dtype=np.int64),
            "x": np.empty((8, 1)),
            "z": np.empty((1, len(surrogate.features))),
            "meas": np.empty((1, len(self.flight_features))),
            "deg": np.empty((1, 2)),
            "feats": np.empty((1, len(self.flight_features))),
            "failed": np.zeros((1, 2), dtype=np.bool_),
            "rul": np.empty((1, 2)),
        }

    # ------------------------------------------------------------------ state
    @property
    def physics(self) -> bool:
        return self.scenario.fidelity == "physics"

    @property
    def crack_fraction(self) -> float:
        return self.crack_m / self.spring_failure_m

    @property
    def wear_fraction(self) -> float:
        return self.wear_m / self.calibration.seal_critical_wear_m

    @property
    def theta(self) -> float:
        """Crack growth multiplier of the fitted spring, C_unit / C_nom."""
        return self.unit.paris_c / self.params.spring.paris_c

    @property
    def wear_multiplier(self) -> float:
        """Wear rate multiplier of the fitted seals, k_w,unit / k_w,nom."""
        return self.unit.wear_rate_m3_n_m / self.params.seal.wear_rate_m3_n_m

    def true_rul_flights(self) -> tuple[float, float]:
        """Expected flights to failure of (spring, seal) at the units' own rates (inf if the
        fault is inactive or the crack is dormant below the threshold)."""
        x, out = self._scratch["x"], self._scratch["rul"]
        x[0, 0], x[1, 0], x[2, 0] = self.crack_m, self.wear_m, self.spring_failure_m
        x[3, 0], x[4, 0] = self.theta, self.wear_multiplier
        t = self.kernel_tables
        true_rul(x[0], x[1], x[2], x[3], x[4], *t["damage"], *t["rul_consts"], out)
        return float(out[0, 0]), float(out[0, 1])

    def export_state(self, a: dict[str, np.ndarray], row: int) -> None:
        """Write this actuator's state into row ``row`` of a fleet's arrays
        (:class:`scas_env.fleet_state.FleetState`)."""
        a["crack"][row], a["wear"][row] = self.crack_m, self.wear_m
        a["fail"][row] = self.spring_failure_m
        a["theta"][row], a["wmult"][row] = self.theta, self.wear_multiplier
        a["unit_z"][row] = self.unit_z
        a["life"][row] = self.life_left["spring"], self.life_left["seal"]
        a["upcoming"][row] = self.upcoming["spring"], self.upcoming["seal"]

    def import_flight_state(self, a: dict[str, np.ndarray], row: int) -> None:
        """Take back what flights on the fleet's fast path changed: crack, wear, lives left."""
        self.crack_m, self.wear_m = float(a["crack"][row]), float(a["wear"][row])
        self.life_left["spring"], self.life_left["seal"] = a["life"][row].tolist()

    # ------------------------------------------------------------------ life cycle
    def reset(
        self,
        rng: np.random.Generator,
        part_rngs: dict[str, np.random.Generator] | None = None,
    ) -> None:
        """A new actuator: new unit, new parts (or parts part-way through life).

        ``part_rngs`` (``"per_part"`` draws): the parts streams of springs and seals, which
        supply the fitted spring pair and seal set (and their growth streams).
        """
        if self.per_part != (part_rngs is not None):
            raise ValueError(
                "part_rngs must be given exactly when Scenario.degradation_draws is 'per_part'"
            )
        self.unit = draw_unit(self.params, rng)
        if self.physics:
            # the episode's window library (scenario.window_library): windows drawn lazily
            # from their own seeds, each with its healthy baseline simulated once
            self._library_seed = int(rng.integers(0, 2**63 - 1))
            self._windows: dict[int, FlightWindow] = {}
        if part_rngs is None:
            self._fit_spring(self.unit, rng)
        else:
            self._fit_spring(draw_unit(self.params, part_rngs["spring"]), part_rngs["spring"])
            seal = draw_unit(self.params, part_rngs["seal"])
            self.unit = replace(self.unit, wear_rate_m3_n_m=seal.wear_rate_m3_n_m)
        self.wear_m = 0.0
        if self.scenario.initial_health == "random":
            life_used = rng.random(2)
            if (
                self.scenario.crack_active
                and self.crack_m >= self.calibration.crack_dormant_below_m
            ):
                start = float(self._table.damage(np.array([self.crack_m]))[0])
                end = float(self._table.damage(np.array([self.spring_failure_m]))[0])
                self.crack_m = float(
                    self._table.inverse_damage(np.array([start + life_used[0] * (end - start)]))[0]
                )
            if self.scenario.wear_active:
                self.wear_m = life_used[1] * self.calibration.seal_critical_wear_m
        if part_rngs is not None:
            for part in PARTS:
                self._new_growth(part, part_rngs[part])

    def _fit_spring(self, donor: UnitSample, rng: np.random.Generator) -> None:
        """Fit the spring pair (geometry, Paris C, initial flaw) of ``donor``."""
        self.unit = replace(
            self.unit,
            wire_diameter_m=donor.wire_diameter_m,
            mean_coil_diameter_m=donor.mean_coil_diameter_m,
            paris_c=donor.paris_c,
            initial_crack_m=donor.initial_crack_m,
        )
        self.crack_m = donor.initial_crack_m if self.scenario.crack_active else 0.0
        self.unit_z = self.surrogate.draw_unit_z(rng, self._unit_z_draws)
        if self.physics:
            self.spring_failure_m = failure_depth_from_params(
                self.params,
                wire_diameter_m=self.unit.wire_diameter_m[CRACKED_SPRING],
                coil_diameter_m=self.unit.mean_coil_diameter_m[CRACKED_SPRING],
            ).depth_m
            self._growth = growth_model(self.params, self.unit)

    def replace(self, part: str, rng: np.random.Generator) -> None:
        """Fit a new spring pair (``"spring"``) or a new seal set (``"seal"``), drawn from
        ``rng`` (``"per_part"``: that part's parts stream, which also seeds its growth)."""
        if part not in PARTS:
            raise ValueError(f"part = {part!r} must be one of {PARTS}")
        donor = draw_unit(self.params, rng)
        if part == "spring":
            self._fit_spring(donor, rng)
        else:
            self.unit = replace(self.unit, wear_rate_m3_n_m=donor.wear_rate_m3_n_m)
            self.wear_m = 0.0
        if self.per_part:
            self._new_growth(part, rng)

    # ------------------------------------------------------------------ per-part lives
    def _new_growth(self, part: str, rng: np.random.Generator) -> None:
        """The fitted ``part``'s own growth-factor stream, seeded from ``rng``, and its life."""
        seed = int(rng.integers(0, 2**63 - 1))
        values, position = self.buffer_storage.get(f"{part}_growth", (None, None))
        self.growth[part] = NormalBuffer(np.random.default_rng(seed), values, position)
        self.life_left[part] = self.flights_to_failure(part)
        if self._look_ahead:
            self.upcoming[part] = self.next_lives(part, rng, UPCOMING_PARTS)

    def next_lives(self, part: str, rng: np.random.Generator, count: int) -> list[float]:
        """``"per_part"``: the whole lives (flights) of the next ``count`` parts of this kind
        that ``rng`` (the kind's parts stream; not moved) will supply: what a clairvoyant
        oracle knows. The world itself is not changed."""
        if not self.per_part:
            raise ValueError("next_lives needs Scenario.degradation_draws = 'per_part'")
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise ValueError(f"count = {count!r} must be an integer >= 0")
        clone = copy.copy(self)
        clone.growth, clone.buffer_storage = dict(self.growth), {}
        clone.life_left, clone._look_ahead = dict(self.life_left), False
        rng = copy.deepcopy(rng)
        lives = []
        for _ in range(count):
            clone.replace(part, rng)
            lives.append(clone.life_left[part])
        return lives

    def flights_to_failure(self, part: str) -> float:
        """``"per_part"``: the flights ``part`` will still fly, the failing one included, at
        its own future growth draws (a copy of its stream is replayed; inf if the fault is
        inactive or the crack dormant)."""
        if not self.per_part:
            raise ValueError("flights_to_failure needs Scenario.degradation_draws = 'per_part'")
        cal, t = self.calibration, self.kernel_tables
        if part == "spring":
            if not self.scenario.crack_active or self.crack_m < cal.crack_dormant_below_m:
                return math.inf
        elif not self.scenario.wear_active:
            return math.inf
        draws = copy.deepcopy(self.growth[part])  # the same future normals, original unmoved
        state = np.array([self.crack_m if part == "spring" else self.wear_m])
        flown = 0
        while flown < _MAX_LIFE_FLIGHTS:
            z = draws.standard_normal(draws.values.size)
            if part == "spring":
                k = crack_flights_to_failure(
                    float(state[0]), self.spring_failure_m, self.theta, z, *t["damage"],
                    *t["flight_consts"][:3], state,
                )  # fmt: skip
            else:
                k = wear_flights_to_failure(
                    float(state[0]), cal.wear_rate_m_per_flight * self.wear_multiplier,
                    self._wear_cv, cal.seal_critical_wear_m, z, state,
                )  # fmt: skip
            if k > 0:
                return float(flown + k)
            flown += z.size
        return math.inf

    def _library_window(self, rng: np.random.Generator) -> FlightWindow | None:
        """This flight's window from the library (None: draw a new one from ``rng``)."""
        size = int(self.scenario.window_library)
        if size == 0:
            return None
        k = int(rng.integers(size))
        if k not in self._windows:
            seeded = np.random.default_rng((self._library_seed, k))
            self._windows[k] = draw_window(self.params, seeded, self.params.mission.flight_window_s)
        return self._windows[k]

    # ------------------------------------------------------------------ measurements
    def _config(self, rng: np.random.Generator):
        health = HealthState(crack_depth_m=self.crack_m, seal_wear_m=self.wear_m)
        conditions = draw_run_conditions(self.params, rng)
        return actuator_config(self.params, unit=self.unit, conditions=conditions, health=health)

    def _surrogate_features(
        self, names: tuple[str, ...], idx: list[int], rng: np.random.Generator
    ) -> dict[str, float]:
        c, w = min(self.crack_fraction, 1.0), min(self.wear_fraction, 1.0)
        values = self.surrogate.sample_list(c, w, self.unit_z, rng, idx)
        return dict(zip(names, values, strict=True))

    def test(self, rng: np.random.Generator) -> dict[str, float]:
        """Run the pre-flight test; returns G1 (A) and G3 (A/m)."""
        if self.physics:
            feats = ground_test(self.params, self._config(rng), rng).features
            return {f: feats[f] for f in GROUND_FEATURES}
        return self._surrogate_features(GROUND_FEATURES, self._ground_feature_idx, rng)

    def installation_reference(self, rng: np.random.Generator, n_tests: int) -> dict[str, float]:
        """The installation's reference reading of each ground feature, as recorded at
        fitting: the mean of ``n_tests`` pre-flight tests of this installation with healthy
        parts (its tolerances and installation effects included; ``scas_env.acceptance``)."""
        crack, wear = self.crack_m, self.wear_m
        self.crack_m, self.wear_m = 0.0, 0.0
        try:
            tests = [self.test(rng) for _ in range(n_tests)]
        finally:
            self.crack_m, self.wear_m = crack, wear
        return {f: math.fsum(t[f] for t in tests) / n_tests for f in GROUND_FEATURES}

    def fly(self, rng: np.random.Generator, degradation_rng: np.random.Generator) -> FlightResult:
        """Fly one flight: measure (``rng``), degrade, report failures.

        The surrogate draws the flight's two degradation factors from ``degradation_rng``
        (two normals per flight, whatever else happens); the physics takes its damage from
        the simulated window, drawn from ``rng``.
        """
        cal = self.calibration
        if self.physics:
            config = self._config(rng)
            window = flight_window(
                self.params,
                config,
                rng,
                self.params.mission.flight_window_s,
                window=self._library_window(rng),
            )
            feats = {f: window.features[f] for f in self.flight_features}
            loads = flight_loads_from_run(
                window.run, self.params.mission.flight_duration_s, config.spring_rate_1_n_m
            )
            d_crack = (
                crack_increment_m(self.params, self.unit, self._growth, self.crack_m, loads)
                if self.scenario.crack_active
                else 0.0
            )
            new_crack = self.crack_m + d_crack
            d_wear = (
                wear_increment_m(self.params, self.unit, loads)
                if self.scenario.wear_active
                else 0.0
            )
            new_wear = self.wear_m + d_wear
        else:
            sc = self._scratch
            sc["meas"][0] = rng.standard_normal(len(self.flight_features))
            if self.per_part:
                sc["deg"][0, 0] = self.growth["spring"].standard_normal(1)[0]
                sc["deg"][0, 1] = self.growth["seal"].standard_normal(1)[0]
                for part in PARTS:
                    self.life_left[part] -= 1.0
            else:
                sc["deg"][0] = degradation_rng.standard_normal(2)
            sc["z"][0] = self.unit_z
            x = sc["x"]
            x[0, 0], x[1, 0], x[2, 0] = self.crack_m, self.wear_m, self.spring_failure_m
            x[3, 0], x[4, 0] = self.theta, self.wear_multiplier
            t = self.kernel_tables
            surrogate_flights(
                sc["envs"], x[0], x[1], x[2], x[3], x[4], sc["z"], sc["meas"], sc["deg"],
                *t["flight"], *t["damage"], *t["flight_consts"],
                x[5], x[6], sc["feats"], sc["failed"],
            )  # fmt: skip
            new_crack, new_wear = float(x[5, 0]), float(x[6, 0])
            feats = dict(zip(self.flight_features, sc["feats"][0].tolist(), strict=True))
        failed = []
        if new_crack >= self.spring_failure_m:
            failed.append("spring")
        if new_wear >= cal.seal_critical_wear_m:
            failed.append("seal")
        self.crack_m, self.wear_m = new_crack, new_wear
        if failed:
            feats = {f: math.nan for f in self.flight_features}
        return FlightResult(feats, tuple(failed))


#: Parts of each kind whose lives the clairvoyant view holds ahead of the fitted one.
UPCOMING_PARTS = 3
#: Flights after which a life counts as infinite (far beyond any episode).
_MAX_LIFE_FLIGHTS = 10_000_000


def kernel_tables(
    calibration: Calibration,
    surrogate: SurrogateModel,
    scenario: Scenario,
    table: TabulatedRateModel,
) -> dict[str, tuple]:
    """Argument groups of :mod:`scas_env.fleet_kernels` for one world configuration
    (``table``: the calibrated crack-growth table)."""
    cal = calibration
    crack_cv, wear_cv = cal.flight_scatter(scenario.damage_scatter)
    idx = np.array([surrogate.index(f) for f in scenario.flight_feature_names], dtype=np.int64)
    stack = np.stack([surrogate.mean, surrogate.unit_std, surrogate.run_std])
    active = (bool(scenario.crack_active), bool(scenario.wear_active))
    return {
        "flight": (surrogate.crack_grid, surrogate.wear_grid, stack, idx),
        "damage": table.table_args,
        "flight_consts": (
            np.log(cal.crack_cv_depth_m),
            np.asarray(crack_cv, dtype=np.float64),
            float(cal.crack_dormant_below_m),
            wear_cv,
            float(cal.wear_rate_m_per_flight),
            float(cal.seal_critical_wear_m),
            *active,
        ),
        "rul_consts": (
            float(cal.crack_dormant_below_m),
            float(cal.wear_rate_m_per_flight),
            float(cal.seal_critical_wear_m),
            *active,
        ),
    }
