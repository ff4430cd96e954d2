"""``ScasMaintenance-v0``: maintenance of a degrading helicopter SCAS actuator, flight by flight."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from scas_env.acceptance import AirworthinessLimits
from scas_env.actuator.calibration import Calibration, calibration_for
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel, default_surrogate
from scas_env.block_draws import NormalBuffer
from scas_env.costs import CostModel
from scas_env.dashboard import DashboardRenderer
from scas_env.fleet_state import PARTS, REWARD_TERMS, FleetState
from scas_env.info import StepInfo, build_info
from scas_env.monitor import HealthMonitor, learning_features
from scas_env.observation import ObservationBuilder
from scas_env.scenario import Scenario
from scas_env.world import GROUND_FEATURES, ActuatorWorld

#: action types checked without ``Discrete.contains`` (SB3 passes numpy int64)
_PLAIN_INTS = (int, np.int64)

FLY, TEST_AND_FLY, REPLACE_SPRING, REPLACE_SEAL = range(4)
#: Random streams of an episode: new units and parts, per-flight degradation, measurement
#: noise (tests, flight features, physics windows), particle filters.
STREAMS = ("parts", "degradation", "measure", "filter")
ACTION_NAMES = ("fly", "test_and_fly", "replace_spring", "replace_seal")


class ScasMaintenanceEnv(gym.Env):
    """Maintenance of a helicopter SCAS hydraulic actuator with two propagating faults.

    ## Description

    A SCAS (stability and command augmentation system) actuator flies one flight per step.
    One coil of a centering spring carries a fatigue crack that grows by Paris' law with the
    rainflow-counted cycles of each flight; the piston seals wear by Archard's law, which
    opens internal leakage and lowers the loop's bandwidth. Both faults progress at once,
    each unit with its own growth constants. The operator sees only what the avionics
    measure (servovalve current and actuator position, turned into the features of De Martin
    et al. 2020, Table 2) and what a particle filter makes of them. A part that reaches its
    critical value fails in flight: an expensive, unscheduled event. Testing before a flight
    costs a little and measures the on-ground features; replacing a part costs and takes the
    aircraft off the line. The task: most availability for the least cost.

    ## Action Space

    ``Discrete(4)``:

    | action | name | effect |
    |---|---|---|
    | 0 | fly | fly the slot's flight |
    | 1 | test_and_fly | run the pre-flight test (G1, G3); fly only if it passes go/no-go |
    | 2 | replace_spring | fit a new centering-spring pair; the slot (plus downtime) on ground |
    | 3 | replace_seal | fit a new piston-seal set; the slot (plus downtime) on ground |

    While the aircraft is on the ground for earlier downtime, 0 and 1 do nothing and 2, 3
    replace the part at no extra downtime beyond the longest pending one.

    The go/no-go (``Scenario.go_no_go``, :mod:`scas_env.acceptance`): in v0 every ground
    feature must lie inside the healthy population's band (a detector's band, false no-go
    rate ``go_no_go_false_alarm``); the next slot may fly untested. In v1 the test fails when
    a ground feature has moved from the installation's reference (recorded at fitting) as
    far as a part at its critical level would move it (P(no-go) = ``acceptance_catch`` = 0.9
    for a part at critical, ~0 for a healthy unit), and the aircraft then stays on the
    ground (actions 0 fly nothing) until a passing re-test (action 1) or a replacement.
    ``Scenario.preflight="every_flight"`` runs the test before every flight at no cost
    (the paper's power-up test); action 1 then equals action 0.

    ## Observation Space

    ``obs_mode="features+rul"`` (default): ``Box(18,)`` float32, finite bounds
    (``env.unwrapped.obs_names`` and ``obs_units`` name every entry):

    | idx | name | unit | bounds | meaning |
    |---|---|---|---|---|
    | 0 | I2 | - | [-1, 1] | last flight: mean normalised xcorr of i with the healthy baseline |
    | 1 | I6 | mm | [0, 5.2] | last flight: rms of the LVDT position |
    | 2 | I7 | uA/mm | [0, 1e5] | last flight: rms(i) / rms(x) |
    | 3 | G1 | uA | [-1e4, 1e4] | last pre-flight test: mean current |
    | 4 | G3 | uA/mm | [-4e4, 4e4] | last pre-flight test: current / displacement |
    | 5 | test_age | slots | [0, slots] | slots since that test (since reset if none) |
    | 6 | no_go | 0/1 | [0, 1] | that test failed go/no-go (cleared by a replacement) |
    | 7 | spring_rul_mean | flights | [0, cap] | particle-filter RUL of the spring, mean |
    | 8 | spring_rul_low | flights | [0, cap] | its low quantile (``rul_quantile``) |
    | 9 | spring_risk | - | [0, 1] | P(spring fails within ``risk_horizon_flights``) |
    | 10-12 | seal_rul_mean, seal_rul_low, seal_risk | | | the same for the seals |
    | 13 | spring_alarm | 0/1 | [0, 1] | section-5.1 detector on G1 has alarmed |
    | 14 | seal_alarm | 0/1 | [0, 1] | section-5.1 detector on G3 has alarmed |
    | 15 | spring_age | flights | [0, slots] | flights since the spring pair was fitted |
    | 16 | seal_age | flights | [0, slots] | flights since the seals were fitted |
    | 17 | downtime | slots | [0, max] | slots still to spend on the ground |

    v2 (``flight_features="I2,I6,I7,I8,I9"``) adds I8 (uA, mean(i - i_h): the crack's DC
    null-bias current) and I9 (-, rms(i)/rms(i_h): seal wear) after I7, ``Box(20,)``. In v0 and
    v1 the filters learn at tests only; in v2 they also learn from I8 (spring) and I9 (seals)
    every ``flight_update_flights`` flights (docs/beliefs.md). Between updates the RUL entries
    are those of the last update aged by the flights flown since (each particle's RUL falls by
    one per flight; ``scas_env.monitor``). Feature values before the first flight or test are
    the healthy surrogate means. RUL entries saturate at ``rul_cap_flights``; feature entries
    saturate at their bounds (the raw values are in ``info["features"]``). ``"features"``:
    entries 0-6 and 13-17 (no filter). ``"state"``: the truth (an oracle's view): crack fraction
    of critical, wear fraction, true spring RUL, true seal RUL (flights, capped), spring age,
    seal age, downtime. ``"dict"``: a ``Dict`` of all of the above.

    ## Rewards

    Per step, in USD (``CostModel``): ``+flight_value`` for a flight flown, ``-test`` per
    pre-flight test, ``-no_go_inspection`` when the test fails, ``-spring_replacement`` /
    ``-seal_replacement``, and ``-(unscheduled_removal + mission_abort)`` for an in-flight
    failure (the flight earns nothing; failed parts are replaced; ``failure_downtime_slots``
    on the ground). ``info["reward_terms"]`` splits it.

    ## Info

    A dict of scalars and small dicts (``scas_env.info.StepInfo``, a ``dict`` whose deep copy
    is fast: SB3's ``DummyVecEnv`` deep-copies infos each step), its size fixed over the
    episode: ``slot``,
    ``availability`` (flights flown / slots), ``flights``, ``cost_usd`` (costs so far),
    ``revenue_usd``, ``tests``, ``no_go`` (failed tests), ``downtime``; per part
    ``failures`` and ``replacements`` (counts, failures included); ``wasted_life_flights``
    (the true RUL, capped at ``rul_cap_flights``, thrown away by this step's preventive
    replacement of the part, 0 if none), ``wasted_life_sum_flights`` and
    ``wasted_life_count`` (running over the episode's preventive replacements);
    ``reward_terms``; ``features`` (raw latest features, SI units); ``true_state`` (crack
    depth and wear in m and as fractions of critical, true RUL of each part in flights).

    ## Starting State

    A new unit drawn from the design's scatter (spring geometry, Paris constant, initial
    flaw, seal wear rate), new parts (``initial_health="new"``) or each part at a uniform
    fraction of its life (``"random"``); the filters start from their priors.

    ## Episode End

    Truncation after ``episode_slots`` flight slots (default 2000, about 1.7 mean part lives).
    There is no termination: a failure is an event with its cost, not the end.

    ## Arguments

    ``gym.make("scas_env/ScasMaintenance-v0", fidelity=..., obs_mode=..., episode_slots=...,
    n_particles=..., cost_model=CostModel(...), params=ScasParams(...), scenario=Scenario(...))``.
    Keywords are the fields of :class:`~scas_env.scenario.Scenario` (or pass ``scenario``);
    unknown keywords raise ``ValueError``. ``params`` other than the default are calibrated
    from physics at construction (seconds); the feature surrogate is the shipped one.

    ## Vectorised

    ``gym.make_vec("scas_env/ScasMaintenance-v0", num_envs=N,
    vectorization_mode="vector_entry_point")`` is natively batched for the surrogate
    (``scas_env.vector_env``): the episodes of N single envs seeded ``seed + i``, bit for
    bit, next-step autoreset, info as a dict of arrays.

    ## Rendering

    ``render_mode="ansi"``: one line of text. ``"rgb_array"``: the health dashboard
    (:mod:`scas_env.dashboard`: crack and wear against their critical levels, the filters'
    RUL distributions, the latest features, costs and availability) as a (400, 640, 3)
    uint8 frame; ``"human"``: the same in a matplotlib window. ``metadata["render_fps"]``
    is 10.

    ## Version History

    * v0: initial release (18-entry observation with the go/no-go flag; ``info`` of fixed
      size: wasted life as this step's value plus running sum and count).
    * v1: the go/no-go is an airworthiness limit on the deviation from the installation's
      reference and a failed test holds the aircraft on the ground until cleared
      (``go_no_go="airworthiness"``); everything else as v0, which stays registered.
    * v2: v1 plus two in-flight features that see the faults, I8 = mean(i - i_h) (uA, the
      crack's DC null-bias current) and I9 = rms(i)/rms(i_h) (-, seal wear), after I7 in the
      observation (``Box(20,)``), and learnt from by the filters every
      ``flight_update_flights`` flights (``flight_features="I2,I6,I7,I8,I9"``); per-part
      degradation draws (``degradation_draws="per_part"``): each part's life is fixed when
      it is fitted, whatever the policy does (common random numbers per part), the true RUL
      in ``info`` and the ``"state"`` observation is the exact remaining life, and
      :meth:`part_lives` tells a clairvoyant oracle the lives to come. v0 and v1 stay
      registered and unchanged.

    ## Example

    >>> import gymnasium as gym
    >>> import scas_env
    >>> env = gym.make("scas_env/ScasMaintenance-v0")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, env.action_space
    ((18,), Discrete(4))
    >>> obs, reward, terminated, truncated, info = env.step(1)
    >>> float(reward)  # flight value minus the test
    2400.0
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["ansi", "rgb_array", "human"],
        "render_fps": 10,
    }

    def __init__(
        self,
        *,
        scenario: Scenario | None = None,
        cost_model: CostModel | None = None,
        params: ScasParams | None = None,
        calibration: Calibration | None = None,
        surrogate: SurrogateModel | None = None,
        render_mode: str | None = None,
        **scenario_fields: Any,
    ) -> None:
        if scenario is not None and scenario_fields:
            raise ValueError(
                "pass either scenario=Scenario(...) or its fields, not both: "
                f"{sorted(scenario_fields)}"
            )
        self.scenario = scenario if scenario is not None else Scenario.from_dict(scenario_fields)
        self.costs = cost_model if cost_model is not None else CostModel()
        self.params = params if params is not None else ScasParams()
        for name, value, cls in (
            ("scenario", self.scenario, Scenario),
            ("cost_model", self.costs, CostModel),
            ("params", self.params, ScasParams),
        ):
            if not isinstance(value, cls):
                raise ValueError(f"{name} must be a {cls.__name__}, got {type(value).__name__}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(
                f"render_mode = {render_mode!r} must be None or one of "
                f"{self.metadata['render_modes']}"
            )
        self.render_mode = render_mode
        #: the health dashboard (scas_env.dashboard) of the "rgb_array" and "human" modes
        self._renderer = (
            DashboardRenderer(render_mode) if render_mode in DashboardRenderer.MODES else None
        )
        for name, value, cls in (
            ("calibration", calibration, Calibration),
            ("surrogate", surrogate, SurrogateModel),
        ):
            if value is not None and not isinstance(value, cls):
                raise ValueError(
                    f"{name} = {value!r} must be None (the default) or a {cls.__name__}"
                )
        self.calibration = calibration if calibration is not None else calibration_for(self.params)
        self.surrogate = surrogate if surrogate is not None else default_surrogate()
        self.world = ActuatorWorld(self.params, self.scenario, self.calibration, self.surrogate)
        #: airworthiness go/no-go: limits on the ground features' deviation from the
        #: installation's reference (scas_env.acceptance); None for the detection band
        self.limits = (
            AirworthinessLimits.from_surrogate(
                self.surrogate,
                reference_tests=int(self.scenario.reference_tests),
                catch=self.scenario.acceptance_catch,
            )
            if self.scenario.go_no_go == "airworthiness"
            else None
        )
        self.reference: dict[str, float] = {}
        self.builder = ObservationBuilder(self.scenario, self.costs, self.surrogate, self.params)
        self.observation_space = self.builder.space
        self.action_space = spaces.Discrete(4)
        self.obs_names, self.obs_units = self.builder.names, self.builder.units
        self.monitor: HealthMonitor | None = None
        #: this actuator as a fleet of one: observation and info are assembled from it by
        #: the same code as the vector env's (scas_env.fleet_state)
        self.fleet = new_fleet_state(self, 1)
        #: where the surrogate's normal buffers live (the vectorised env points them at rows
        #: of its tables): stream name -> (values, position) arrays
        self.buffer_storage: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    # ------------------------------------------------------------------ gym API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if seed is not None:
            if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
                raise ValueError(f"seed = {seed!r} must be None or an integer >= 0")
            seed = int(seed)  # numpy integers are valid seeds; Gymnasium wants a Python int
        if options is not None and (not isinstance(options, dict) or options):
            raise ValueError(f"options = {options!r}: this env takes no options (None or {{}})")
        super().reset(seed=seed)
        # Independent streams, all seeded from np_random, so that two policies run on the
        # same seed share the units, the parts fitted, and each flight's degradation draw
        # (common random numbers), whatever they test or replace.
        seeds = self.np_random.integers(0, 2**63 - 1, size=len(STREAMS))
        self.rngs = {
            name: np.random.default_rng(int(s)) for name, s in zip(STREAMS, seeds, strict=True)
        }
        if self.scenario.fidelity == "surrogate":
            # The surrogate draws only standard normals from these two streams: hand them
            # out from blocks (the same numbers, fewer calls; scas_env.block_draws).
            for name in ("measure", "degradation"):
                values, position = self.buffer_storage.get(name, (None, None))
                self.rngs[name] = NormalBuffer(self.rngs[name], values, position)
        part_rngs = None
        if self.scenario.degradation_draws == "per_part":
            # springs and seals from their own parts streams (drawn after the four above,
            # so "per_slot" episodes keep their seeds)
            part_seeds = self.np_random.integers(0, 2**63 - 1, size=len(PARTS))
            part_rngs = {
                part: np.random.default_rng(int(s))
                for part, s in zip(PARTS, part_seeds, strict=True)
            }
            for part in PARTS:
                self.rngs[f"{part}_parts"] = part_rngs[part]
            self.world.buffer_storage = self.buffer_storage
        self.world.reset(self.rngs["parts"], part_rngs)
        self._record_reference()
        self.monitor = HealthMonitor(
            self.params, self.scenario, self.calibration, self.surrogate, self.rngs["filter"]
        )
        self.monitor.reset()
        self.slot = 0
        self.downtime = 0
        self.part_age = {"spring": 0, "seal": 0}
        self.stats = _Stats()
        self._wasted_now = dict.fromkeys(PARTS, 0.0)
        self.builder.reset()
        outputs = self._outputs(dict.fromkeys(REWARD_TERMS, 0.0))
        if self._renderer is not None:
            self._renderer.observe(self)
        return outputs

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self.monitor is None:
            raise RuntimeError("call reset() before step()")
        if self.slot >= self.scenario.episode_slots:
            raise RuntimeError(
                f"the episode was truncated at slot {self.slot} (episode_slots = "
                f"{self.scenario.episode_slots}): call reset() before step()"
            )
        if not (type(action) in _PLAIN_INTS and 0 <= action < 4) and not (
            self.action_space.contains(action)  # the general check (0-d arrays, ...)
            or (  # any numpy integer scalar in range (np.uint64 fails Discrete's cast check)
                isinstance(action, np.integer) and 0 <= action < 4
            )
        ):
            raise ValueError(f"action = {action!r} is not in Discrete(4): {ACTION_NAMES}")
        reward, terms = self.advance(int(action))
        truncated = self.slot >= self.scenario.episode_slots
        obs, info = self._outputs(terms)
        if self._renderer is not None:
            self._renderer.observe(self)
        return obs, reward, False, truncated, info

    def wasted_now(self, part: str) -> float:
        """True RUL (flights) thrown away by this slot's preventive replacement of ``part``
        (0 without one): ``info["wasted_life_flights"][part]``."""
        return self._wasted_now[part]

    def advance(self, action: int) -> tuple[float, dict[str, float]]:
        """One slot of a checked ``action`` (int in 0..3) without assembling the observation
        and info: the reward (USD) and its terms. ``step`` is this plus the outputs; the
        native vector env calls it for its slow steps (it assembles its own outputs)."""
        terms = dict.fromkeys(REWARD_TERMS, 0.0)
        self._wasted_now = dict.fromkeys(PARTS, 0.0)
        grounded = self.downtime > 0
        flew = False
        if action in (REPLACE_SPRING, REPLACE_SEAL):
            part = PARTS[action - REPLACE_SPRING]
            self._replace(part, terms, failed=False)
            extra = (
                self.costs.spring_downtime_slots
                if part == "spring"
                else self.costs.seal_downtime_slots
            )
            self.downtime = max(self.downtime, 1 + extra)
        elif not grounded:
            every_flight = self.scenario.preflight == "every_flight"
            # airworthiness: a failed test holds the aircraft until a pass or a replacement
            go = not (self.limits is not None and self.builder.no_go)
            if action == TEST_AND_FLY or every_flight:
                feats = self.world.test(self.rngs["measure"])
                self.monitor.tested(feats)
                go = self._go(feats)
                self.builder.tested(feats, go)
                self.stats.tests += 1
                terms["test"] = 0.0 if every_flight else -self.costs.test_usd
                if not go:
                    self.stats.no_go += 1
                    terms["no_go"] = -self.costs.no_go_inspection_usd
            if go:
                flew = self._fly(terms)
        self.downtime = max(self.downtime - 1, 0)
        self.slot += 1
        self.stats.flown += int(flew)
        self.builder.slot_passed()
        for part in PARTS:
            self.part_age[part] += int(flew)
        reward = float(sum(terms.values()))
        self.stats.cost -= sum(v for k, v in terms.items() if k != "flight")
        self.stats.revenue += terms["flight"]
        return reward, terms

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        super().close()

    def render(self) -> str | np.ndarray | None:
        """``"ansi"``: one line of text; ``"rgb_array"``: the health dashboard as an
        (H, W, 3) uint8 frame; ``"human"``: the dashboard in a window (returns None)."""
        if self._renderer is not None:
            return self._renderer.render(self)
        if self.render_mode != "ansi":
            return None
        w = self.world
        return (
            f"slot {self.slot}: crack {w.crack_m * 1e6:.0f} um ({w.crack_fraction:.0%}), "
            f"wear {w.wear_m * 1e6:.2f} um ({w.wear_fraction:.0%}), downtime {self.downtime}, "
            f"availability {self.stats.flown / max(self.slot, 1):.3f}"
        )

    def part_lives(self, count: int = 2) -> dict[str, list[float]]:
        """Clairvoyance (``Scenario(degradation_draws="per_part")`` only): per part, the
        flights the fitted one will still fly (the failing one included), then the whole
        lives of the next ``count`` replacements, as this episode will hand them out
        whatever the policy does. Nothing in the episode is moved."""
        if self.monitor is None:
            raise RuntimeError("call reset() before part_lives()")
        if not self.world.per_part:
            raise ValueError("part_lives needs Scenario.degradation_draws = 'per_part'")
        return {
            part: [
                self.world.life_left[part],
                *self.world.next_lives(part, self.rngs[f"{part}_parts"], count),
            ]
            for part in PARTS
        }

    # ------------------------------------------------------------------ internals
    def _go(self, feats: dict[str, float]) -> bool:
        """Go/no-go (``Scenario.go_no_go``): every ground feature inside its healthy
        two-sided band, or within the airworthiness limits of the installation's reference."""
        if self.limits is not None:
            return self.limits.passes(feats, self.reference)
        return self.builder.within_acceptance(feats)

    def _record_reference(self) -> None:
        """Airworthiness go/no-go: record the installation's reference at fitting (reset and
        each new spring pair, which brings its own installation effects)."""
        if self.limits is not None:
            self.reference = self.world.installation_reference(
                self.rngs["measure"], int(self.scenario.reference_tests)
            )

    def _fly(self, terms: dict[str, float]) -> bool:
        result = self.world.fly(self.rngs["measure"], self.rngs["degradation"])
        self.monitor.flown(result.features)
        if result.failed:
            terms["failure"] = -self.costs.failure_total_usd
            for part in result.failed:
                self.stats.failures[part] += 1
                self._replace(part, terms, failed=True)
            self.downtime = max(self.downtime, 1 + self.costs.failure_downtime_slots)
            return False
        self.builder.flown(result.features)
        terms["flight"] = self.costs.flight_value_usd
        return True

    def _replace(self, part: str, terms: dict[str, float], *, failed: bool) -> None:
        if self.world.per_part:  # the part's own remaining life
            rul = self.world.life_left[part]
        else:
            rul = self.world.true_rul_flights()[PARTS.index(part)]
        if not failed:
            cost = (
                self.costs.spring_replacement_usd
                if part == "spring"
                else self.costs.seal_replacement_usd
            )
            terms["replacement"] -= cost
            wasted = min(rul, self.scenario.rul_cap_flights)
            self.stats.wasted_life_sum[part] += wasted
            self.stats.wasted_life_count[part] += 1
            self._wasted_now[part] = wasted
        self.stats.replacements[part] += 1
        self.world.replace(part, self.rngs.get(f"{part}_parts", self.rngs["parts"]))
        if part == "spring":
            self._record_reference()
        self.monitor.replaced(part)
        self.builder.part_replaced()
        self.part_age[part] = 0

    # ------------------------------------------------------------------ snapshots
    def export_state(self, fleet: FleetState, row: int) -> None:
        """Write this actuator's whole state into row ``row`` of ``fleet``: the world, the
        monitor, the feature memory and the episode counters (not this step's reward terms)."""
        a, s = fleet.a, self.stats
        self.world.export_state(a, row)
        self.monitor.export_state(a, row, fleet.table_source[row])
        self.builder.export_state(a, row)
        for p, part in enumerate(PARTS):
            a["part_age"][row, p] = self.part_age[part]
            a["failures"][row, p] = s.failures[part]
            a["replacements"][row, p] = s.replacements[part]
            a["wasted_sum"][row, p] = s.wasted_life_sum[part]
            a["wasted_count"][row, p] = s.wasted_life_count[part]
        if self.limits is not None:
            a["reference"][row] = [self.reference[f] for f in GROUND_FEATURES]
        a["downtime"][row], a["slot"][row] = self.downtime, self.slot
        a["flown"][row], a["tests"][row], a["no_go_count"][row] = s.flown, s.tests, s.no_go
        a["cost"][row], a["revenue"][row] = s.cost, s.revenue

    def import_flight_state(self, fleet: FleetState, row: int) -> None:
        """Take back from row ``row`` of ``fleet`` what the vector env's fast path changes
        (crack, wear, flights pending, the last features, ages, slot, downtime, flights
        flown, revenue; a batched test's counters, cost and no-go)."""
        a = fleet.a
        self.world.import_flight_state(a, row)
        self.monitor.import_flight_state(a, row)
        self.builder.import_flight_state(a, row)
        for p, part in enumerate(PARTS):
            self.part_age[part] = int(a["part_age"][row, p])
        self.downtime, self.slot = int(a["downtime"][row]), int(a["slot"][row])
        self.stats.flown, self.stats.revenue = int(a["flown"][row]), float(a["revenue"][row])
        self.stats.tests, self.stats.no_go = int(a["tests"][row]), int(a["no_go_count"][row])
        self.stats.cost = float(a["cost"][row])

    def _outputs(self, terms: dict[str, float]) -> tuple[Any, StepInfo]:
        """Observation and info of this step, assembled from the fleet of one."""
        fleet = self.fleet
        self.export_state(fleet, 0)
        for t, v in terms.items():
            fleet.terms[t][0] = v
        for p, part in enumerate(PARTS):
            fleet.wasted_now[0, p] = self._wasted_now[part]
        rul = fleet.true_rul()
        obs = self.builder.observe(fleet, rul)
        obs = {k: v[0] for k, v in obs.items()} if isinstance(obs, dict) else obs[0]
        return obs, build_info(fleet, rul, self.builder.features, row=0)


def new_fleet_state(env: ScasMaintenanceEnv, n: int) -> FleetState:
    """An ``n``-row :class:`FleetState` sized for ``env``'s surrogate, filters and features."""
    return FleetState(
        n,
        n_unit_features=len(env.surrogate.features),
        n_particles=env.scenario.n_particles,
        n_features=len(env.builder.features),
        seal_critical_m=env.calibration.seal_critical_wear_m,
        kernel_tables=env.world.kernel_tables,
        exact_lives=env.world.per_part,
        n_learning=len(learning_features(env.scenario)),
    )


class _Stats:
    """Running counters of an episode."""

    def __init__(self) -> None:
        self.flown = 0
        self.tests = 0
        self.no_go = 0
        self.cost = 0.0
        self.revenue = 0.0
        self.failures = dict.fromkeys(PARTS, 0)
        self.replacements = dict.fromkeys(PARTS, 0)
        self.wasted_life_sum = dict.fromkeys(PARTS, 0.0)
        self.wasted_life_count = dict.fromkeys(PARTS, 0)


__all__ = ["ACTION_NAMES", "REWARD_TERMS", "ScasMaintenanceEnv", "new_fleet_state"]
