"""``ScasMaintenance-v2``: maintenance of a degrading helicopter SCAS actuator, flight by flight."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from scas_env.actuator.calibration import Calibration, env_calibration
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel, shipped_surrogate_for
from scas_env.core.batch import ActuatorBatch
from scas_env.core.costs import CostModel
from scas_env.core.info import StepInfo, build_info
from scas_env.core.mismatch import Mismatch
from scas_env.core.observation import ObservationLayout
from scas_env.core.parts import next_lives
from scas_env.core.scenario import Scenario
from scas_env.core.setup import PARTS, Setup
from scas_env.dashboard import DashboardRenderer

FLY, TEST_AND_FLY, REPLACE_SPRING, REPLACE_SEAL = range(4)
ACTION_NAMES = ("fly", "test_and_fly", "replace_spring", "replace_seal")
#: action types checked without ``Discrete.contains`` (SB3 passes numpy int64)
_PLAIN_INTS = (int, np.int64)


def maintenance_mask(downtime: Any, spring_age: Any, seal_age: Any) -> np.ndarray:
    """Valid per-flight actions (bool, shape ``(..., 4)``) from downtime (slots) and part ages
    (flights): ``fly`` always; ``test_and_fly`` iff ``downtime == 0``; ``replace_spring`` iff
    ``spring_age > 0``; ``replace_seal`` iff ``seal_age > 0``.

    >>> maintenance_mask(0, 0, 0).tolist()
    [True, True, False, False]
    >>> maintenance_mask([1, 0], [5, 5], [0, 7]).tolist()
    [[True, False, True, False], [True, True, True, True]]
    """
    down, spring, seal = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (downtime, spring_age, seal_age))
    )
    mask = np.empty((*down.shape, len(ACTION_NAMES)), dtype=bool)
    mask[..., 0] = True  # fly
    mask[..., 1] = down <= 0  # test_and_fly
    mask[..., 2] = spring > 0  # replace_spring
    mask[..., 3] = seal > 0  # replace_seal
    return mask


def make_setup(
    scenario: Scenario | None,
    cost_model: CostModel | None,
    params: ScasParams | None,
    calibration: Calibration | None,
    surrogate: SurrogateModel | None,
    scenario_fields: dict[str, Any],
    mismatch: Mismatch | None = None,
    world_surrogate: SurrogateModel | None = None,
) -> Setup:
    """The :class:`~scas_env.core.setup.Setup` of an env's keywords, each checked."""
    if scenario is not None and scenario_fields:
        raise ValueError(
            f"pass either scenario=Scenario(...) or its fields, not both: {sorted(scenario_fields)}"
        )
    for name, value, cls in (
        ("scenario", scenario, Scenario),
        ("cost_model", cost_model, CostModel),
        ("params", params, ScasParams),
        ("calibration", calibration, Calibration),
        ("surrogate", surrogate, SurrogateModel),
        ("mismatch", mismatch, Mismatch),
        ("world_surrogate", world_surrogate, SurrogateModel),
    ):
        if value is not None and not isinstance(value, cls):
            raise ValueError(f"{name} = {value!r} must be None (the default) or a {cls.__name__}")
    scenario = scenario if scenario is not None else Scenario.from_dict(scenario_fields)
    params = params if params is not None else ScasParams()
    # before the calibration, which other params build in minutes
    surrogate = surrogate if surrogate is not None else shipped_surrogate_for(params)
    return Setup(
        params=params,
        scenario=scenario,
        costs=cost_model if cost_model is not None else CostModel(),
        calibration=calibration if calibration is not None else env_calibration(params),
        surrogate=surrogate,
        mismatch=mismatch if mismatch is not None else Mismatch(),
        world_surrogate=world_surrogate,
    )


class ScasMaintenanceEnv(gym.Env):
    """Maintenance of a helicopter SCAS hydraulic actuator with two propagating faults.

    ## Description

    A SCAS (stability and command augmentation system) actuator flies one flight per step.
    One coil of a centering spring carries a fatigue crack that grows by Paris' law with the
    rainflow-counted cycles of each flight; the piston seals wear by Archard's law, which
    opens internal leakage and lowers the loop's bandwidth. Both faults progress at once,
    each part with its own growth constant and its own flight-to-flight growth draws, so its
    life is fixed when it is fitted. The operator sees only what the avionics measure
    (servovalve current and actuator position, turned into the features of De Martin et al.
    2020, Table 2, and two in-flight features that see the faults) and what two particle
    filters make of them. A part that reaches its critical value fails in flight: an
    expensive, unscheduled event. The pre-flight test measures the on-ground features and is
    an airworthiness check; replacing a part costs and takes the aircraft off the line. The
    task: most availability for the least cost.

    ## Action Space

    ``Discrete(4)``:

    | action | name | effect |
    |---|---|---|
    | 0 | fly | fly the slot's flight (nothing while on the ground or held by a failed test) |
    | 1 | test_and_fly | run the pre-flight test (G1, G3); fly if it passes go/no-go |
    | 2 | replace_spring | fit a new centering-spring pair; the slot (plus downtime) on ground |
    | 3 | replace_seal | fit a new piston-seal set; the slot (plus downtime) on ground |

    While the aircraft is on the ground for earlier downtime, 0 and 1 do nothing and 2, 3
    replace the part at no extra downtime beyond the longest pending one. ``action_masks()``
    (MaskablePPO's protocol) marks the useful ones: no test on the ground, no replacement of
    a part that has not flown (both allowed, neither does anything useful).

    The go/no-go is an airworthiness limit (:mod:`scas_env.core.acceptance`): the test fails
    when a ground feature has moved from the installation's reference (recorded at fitting)
    as far as a part at its critical level would move it (a part at critical fails with
    probability ``acceptance_catch`` = 0.9, a healthy unit almost never). A failed test holds
    the aircraft on the ground (actions 0 fly nothing) until a passing re-test (action 1) or a
    replacement. ``Scenario.preflight="every_flight"`` runs the test before every flight at
    no cost (the paper's power-up test); action 1 then equals action 0.

    ## Observation Space

    ``obs_mode="features+rul"`` (default): ``Box(20,)`` float32, finite bounds
    (``env.unwrapped.obs_names`` and ``obs_units`` name every entry):

    | idx | name | unit | bounds | meaning |
    |---|---|---|---|---|
    | 0 | I2 | - | [-1, 1] | last flight: mean normalised xcorr of i with the healthy baseline |
    | 1 | I6 | mm | [0, 5.2] | last flight: rms of the LVDT position |
    | 2 | I7 | uA/mm | [0, 1e5] | last flight: rms(i) / rms(x) |
    | 3 | I8 | uA | [-1e4, 1e4] | last flight: mean(i - i_h), the crack's DC null-bias current |
    | 4 | I9 | - | [0, 100] | last flight: rms(i) / rms(i_h), seal wear |
    | 5 | G1 | uA | [-1e4, 1e4] | last pre-flight test: mean current |
    | 6 | G3 | uA/mm | [-4e4, 4e4] | last pre-flight test: current / displacement |
    | 7 | test_age | slots | [0, slots] | slots since that test (since reset if none) |
    | 8 | no_go | 0/1 | [0, 1] | that test failed go/no-go (until a passing test or a replacement) |
    | 9 | spring_rul_mean | flights | [0, cap] | particle-filter RUL of the spring, mean |
    | 10 | spring_rul_low | flights | [0, cap] | its low quantile (``rul_quantile``) |
    | 11 | spring_risk | - | [0, 1] | P(spring fails within ``risk_horizon_flights``) |
    | 12-14 | seal_rul_mean, seal_rul_low, seal_risk | | | the same for the seals |
    | 15 | spring_alarm | 0/1 | [0, 1] | section-5.1 detector on G1 has alarmed |
    | 16 | seal_alarm | 0/1 | [0, 1] | section-5.1 detector on G3 has alarmed |
    | 17 | spring_age | flights | [0, slots] | flights since the spring pair was fitted |
    | 18 | seal_age | flights | [0, slots] | flights since the seals were fitted |
    | 19 | downtime | slots | [0, max] | slots still to spend on the ground |

    The filters learn from every pre-flight test (G1 into the spring's, G3 into the seals')
    and, every ``flight_update_flights`` flights, from the batch's means of I8 (spring) and
    I9 (seals); each feature's installation effect is a filter state (docs/prognostics.md).
    Between updates the RUL entries are those of the last update aged by the flights flown
    since. Feature values before the first flight or test are the healthy surrogate means.
    RUL entries saturate at ``rul_cap_flights``; feature entries at their bounds (the raw
    values are in ``info["features"]``); ages at ``episode_slots`` (an ``"in_service"``
    part older than that at reset reads as the bound until it is replaced). ``"features"``:
    entries 0-8 and 15-19 (no filter entries).
    ``"state"``: the truth (an oracle's view): crack fraction of critical, wear fraction,
    each part's remaining life, spring age, seal age, downtime, then the whole lives of the
    next three springs and seals the episode will fit. ``"dict"``: a ``Dict`` of all groups.

    ## Rewards

    Per step, in USD (``CostModel``): ``+flight_value`` for a flight flown, ``-test`` per
    pre-flight test, ``-no_go_inspection`` when the test fails, ``-spring_replacement`` /
    ``-seal_replacement``, and ``-(unscheduled_removal + mission_abort)`` for an in-flight
    failure (the flight earns nothing; failed parts are replaced, priced within the failure:
    ``info["replacements"]`` counts them, the ``replacement`` term does not;
    ``failure_downtime_slots`` on the ground). ``info["reward_terms"]`` splits it.

    ## Info

    A dict of scalars and small dicts (:class:`~scas_env.core.info.StepInfo`, whose deep copy
    is fast: SB3's ``DummyVecEnv`` deep-copies infos each step), of fixed size: ``slot``,
    ``availability`` (flights flown / slots), ``flights``, ``cost_usd`` (costs so far),
    ``revenue_usd``, ``tests``, ``no_go`` (failed tests), ``downtime``; per part
    ``failures`` and ``replacements`` (counts, failures included); ``wasted_life_flights``
    (the true remaining life, capped at ``rul_cap_flights``, thrown away by this step's
    preventive replacement of the part, 0 if none), ``wasted_life_sum_flights`` and
    ``wasted_life_count`` (running over the episode's preventive replacements);
    ``reward_terms``; ``features`` (raw latest features, SI units); ``true_state`` (crack
    depth and wear in m and as fractions of critical, each part's remaining life in flights,
    the failing one included; inf for a part that never fails: a crack fitted below the
    dormant depth, a fault switched off).

    ## Starting State

    A new unit drawn from the design's scatter (spring geometry, Paris constant, initial
    flaw, seal wear rate), new parts (``initial_health="new"``) or each part at a uniform
    fraction of its life (``"random"``: its earlier life unknown, so its age counts from the
    reset and the decision-epoch mask allows replacing it once it has flown; ``"in_service"``
    gives parts with known ages); the filters start from their priors.

    ## Episode End

    Truncation after ``episode_slots`` flight slots (default 2000, about 1.7 mean part lives).
    There is no termination: a failure is an event with its cost, not the end.
    ``spec.max_episode_steps`` is None (the env truncates itself): read
    ``scenario.episode_slots``. A step that raises (a particle-filter update failing, e.g.
    a particle beyond the representable range) leaves the state undefined: the next step
    asks for ``reset()``.

    ## Arguments

    ``gym.make("scas_env/ScasMaintenance-v2", fidelity=..., obs_mode=..., episode_slots=...,
    n_particles=..., cost_model=CostModel(...), params=ScasParams(...), scenario=Scenario(...))``.
    Keywords are the fields of :class:`~scas_env.core.scenario.Scenario` (or pass
    ``scenario``); unknown keywords raise ``ValueError``. ``fidelity="physics"`` simulates the
    actuator for every test and flight window (the parts grow as in the surrogate fidelity).
    ``params`` other than the default are calibrated from physics at construction, and need
    a ``surrogate`` of their own unless they differ in degradation constants only
    (:data:`scas_env.actuator.surrogate.DEGRADATION_ONLY`);
    ``calibration=Calibration(...)`` (:mod:`scas_env.actuator.calibration`: the parts'
    failure thresholds and lives) and ``surrogate=SurrogateModel(...)``
    (:mod:`scas_env.actuator.surrogate`: the feature surrogate the world and the monitor use)
    replace the shipped ones.
    ``mismatch=Mismatch(...)`` (:mod:`scas_env.core.mismatch`) makes the world run other
    growth, scatter or sensing constants than the monitor's filters assume (default: none);
    ``world_surrogate=SurrogateModel(...)`` draws the world's features from another feature
    surrogate than the monitor's ``surrogate`` (e.g. one built at another fluid temperature).
    Estimator options of the monitor (off by default; docs/beliefs.md):
    ``rejuvenation="resample_move"`` and ``cross_variance_inflation=50`` bring the spring's
    RUL intervals to exact Bayes on the same data; with a test before every flight,
    ``rejuvenation="resample_move"``, ``cross_variance_inflation=500`` and
    ``seal_cross_persistence=0.9954`` (the seal filter carries the spring estimate's error as
    a persistent per-particle offset) cover both parts' (0.88-0.90 per life stage); the
    seal's low quantile is still undercut 8.4 % early in its life (docs/findings.md#beliefs).

    ## Vectorised

    ``gym.make_vec("scas_env/ScasMaintenance-v2", num_envs=N,
    vectorization_mode="vector_entry_point")`` steps N actuators as one batch
    (:class:`scas_env.vector_env.ScasMaintenanceVectorEnv`): the episodes of N single envs
    seeded ``seed + i``, bit for bit, next-step autoreset, info as a dict of arrays.

    ## Rendering

    ``render_mode="ansi"``: one line of text. ``"rgb_array"``: the health dashboard
    (:mod:`scas_env.dashboard`) as a (400, 640, 3) uint8 frame; ``"human"``: the same in a
    matplotlib window, drawn by ``reset`` and every ``step``. ``metadata["render_fps"]`` is 10.

    ## Version History

    * v2: the current version (in-flight features I8 and I9 that see the faults and feed
      the filters, the pre-flight test as an airworthiness limit, each part's life fixed at
      fitting, the whole-flight growth scatter; both fidelities). Unreleased fix: a fault
      switched off (``crack_active`` or ``wear_active`` 0) is known to the monitor. Known
      defects kept bit for bit until the next version (the low quantile at exact ties, a
      cloud wholly past critical): docs/findings.md, "Known defects".
    * v0 and v1 are retired (CHANGELOG.md).

    ## Example

    >>> import gymnasium as gym
    >>> import scas_env
    >>> env = gym.make("scas_env/ScasMaintenance-v2")
    >>> obs, info = env.reset(seed=0)
    >>> obs.shape, env.action_space
    ((20,), Discrete(4))
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
        mismatch: Mismatch | None = None,
        world_surrogate: SurrogateModel | None = None,
        render_mode: str | None = None,
        **scenario_fields: Any,
    ) -> None:
        if render_mode is not None and (
            not isinstance(render_mode, str) or render_mode not in self.metadata["render_modes"]
        ):
            raise ValueError(
                f"render_mode = {render_mode!r} must be None or one of "
                f"{self.metadata['render_modes']}"
            )
        self.setup = make_setup(scenario, cost_model, params, calibration, surrogate,
                                scenario_fields, mismatch, world_surrogate)  # fmt: skip
        self.render_mode = render_mode
        #: the health dashboard (scas_env.dashboard) of the "rgb_array" and "human" modes
        self._renderer = (
            DashboardRenderer(render_mode) if render_mode in DashboardRenderer.MODES else None
        )
        self.layout = ObservationLayout(self.setup.scenario, self.setup.costs)
        self.observation_space = self.layout.space
        self.action_space = spaces.Discrete(4)
        self.obs_names, self.obs_units = self.layout.names, self.layout.units
        #: this actuator: a batch of one
        self.batch = ActuatorBatch(self.setup, 1)
        self._row = np.zeros(1, dtype=np.int64)
        self._action = np.zeros(1, dtype=np.int64)
        self._started = False

    # ------------------------------------------------------------------ the setup
    scenario = property(lambda self: self.setup.scenario)
    costs = property(lambda self: self.setup.costs)
    params = property(lambda self: self.setup.params)
    calibration = property(lambda self: self.setup.calibration)
    surrogate = property(lambda self: self.setup.surrogate)

    @property
    def slot(self) -> int:
        """Slots of this episode so far."""
        return int(self.batch.a["slot"][0])

    @property
    def downtime(self) -> int:
        """Slots still to spend on the ground."""
        return int(self.batch.a["downtime"][0])

    @property
    def part_age(self) -> dict[str, int]:
        """Flights since each part was fitted."""
        return dict(zip(PARTS, self.batch.a["part_age"][0].tolist(), strict=True))

    def action_masks(self) -> np.ndarray:
        """Valid actions now (bool, ``(4,)``; MaskablePPO's protocol, :func:`maintenance_mask`):
        no test while on the ground, no replacement of a part that has not flown."""
        if not self._started:
            raise RuntimeError("call reset() before action_masks()")
        a = self.batch.a
        return maintenance_mask(a["downtime"][0], a["part_age"][0, 0], a["part_age"][0, 1])

    # ------------------------------------------------------------------ gym API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if seed is not None:
            if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
                raise ValueError(f"seed = {seed!r} must be None or an integer >= 0")
            seed = int(seed)  # numpy integers are valid seeds; Gymnasium wants a Python int
        if options is not None and (not isinstance(options, dict) or options):
            raise ValueError(f"options = {options!r}: this env takes no options (None or {{}})")
        super().reset(seed=seed)
        self.batch.reset(self._row, [self.np_random])
        self._started = True
        out = self._outputs()
        if self._renderer is not None:
            self._renderer.observe(self)
            if self.render_mode == "human":  # Gymnasium: human mode draws in reset and step
                self._renderer.render(self)
        return out

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        a = self.batch.a
        if a["slot"][0] >= self.setup.scenario.episode_slots:
            raise RuntimeError(
                f"the episode was truncated at slot {self.slot} (episode_slots = "
                f"{self.setup.scenario.episode_slots}): call reset() before step()"
            )
        if (
            not (type(action) in _PLAIN_INTS and 0 <= action < 4)
            and not (
                isinstance(action, np.integer | np.ndarray)
                and np.ndim(action) == 0
                and np.asarray(action).dtype.kind in "iu"  # not timedelta64 (a numpy integer)
                and 0 <= action < 4
            )
            and not (  # an int subclass (IntEnum), as Discrete.contains accepts; not a bool
                isinstance(action, int) and not isinstance(action, bool) and 0 <= action < 4
            )
        ):
            raise ValueError(f"action = {action!r} is not in Discrete(4): {ACTION_NAMES}")
        self._action[0] = action
        try:  # reset_needed_on_error inline (a hot path: no context manager)
            self.batch.slot(self._row, self._action)
            truncated = bool(a["slot"][0] >= self.setup.scenario.episode_slots)
            obs, info = self._outputs()
        except BaseException:
            self._started = False
            raise
        if self._renderer is not None:
            self._renderer.observe(self)
            if self.render_mode == "human":
                self._renderer.render(self)
        return obs, float(a["reward"][0]), False, truncated, info

    def _outputs(self) -> tuple[Any, StepInfo]:
        obs = self.layout.observe(self.batch)
        obs = {k: v[0] for k, v in obs.items()} if isinstance(obs, dict) else obs[0]
        return obs, build_info(self.batch, 0)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        super().close()

    def render(self) -> str | np.ndarray | None:
        """``"ansi"``: one line of text; ``"rgb_array"``: the health dashboard as an
        (H, W, 3) uint8 frame; ``"human"``: the dashboard in a window (returns None);
        no render mode: None.

        With a render mode, before :meth:`reset` (or after a step that raised) there is no
        episode to draw: ``RuntimeError``, as :meth:`step` and :meth:`action_masks` raise,
        following Gymnasium's convention that ``render()`` needs a ``reset()`` first (the
        ``OrderEnforcing`` wrapper of ``gym.make`` raises ``ResetNeeded``)."""
        if self.render_mode is not None and not self._started:
            raise RuntimeError("call reset() before render()")
        if self._renderer is not None:
            return self._renderer.render(self)
        if self.render_mode != "ansi":
            return None
        a = self.batch.a
        crack, wear = float(a["crack"][0]), float(a["wear"][0])
        flown, slot = int(a["flown"][0]), self.slot
        return (
            f"slot {slot}: crack {crack * 1e6:.0f} um ({crack / a['fail'][0]:.0%}), wear "
            f"{wear * 1e6:.2f} um ({wear / self.calibration.seal_critical_wear_m:.0%}), "
            f"downtime {self.downtime}, availability {flown / slot if slot else 1.0:.3f}"
        )

    def part_lives(self, count: int = 2) -> dict[str, list[float]]:
        """Clairvoyance: per part, the flights the fitted one will still fly (the failing one
        included), then the whole lives of the next ``count`` replacements, as this episode
        will hand them out whatever the policy does. Nothing in the episode is moved."""
        if not self._started:
            raise RuntimeError("call reset() before part_lives()")
        life = self.batch.a["life"][0]
        return {
            part: [float(life[p]), *next_lives(self.batch, 0, part, count)]
            for p, part in enumerate(PARTS)
        }


__all__ = ["ACTION_NAMES", "FLY", "REPLACE_SEAL", "REPLACE_SPRING", "TEST_AND_FLY",
           "ScasMaintenanceEnv", "make_setup"]  # fmt: skip
