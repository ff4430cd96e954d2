"""``ScasFleet-v0``: a fleet of helicopters with three SCAS actuators each, day by day."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from scas_env.actuator.calibration import Calibration, env_calibration
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel, shipped_surrogate_for
from scas_env.core.batch import reset_needed_on_error
from scas_env.core.costs import CostModel
from scas_env.core.fleet.batch import MAINTENANCE_CHOICES, FleetBatch
from scas_env.core.fleet.config import FleetConfig
from scas_env.core.fleet.view import FleetView, check_obs_mode
from scas_env.core.scenario import Scenario
from scas_env.core.setup import Setup
from scas_env.fleet_dashboard import draw_fleet, render_text

#: the actuators' scenario of a fleet unless given: parts part-way through life, ages known
FLEET_SCENARIO = {"initial_health": "in_service"}


def make_fleet_setup(
    fleet: FleetConfig | None,
    scenario: Scenario | None,
    cost_model: CostModel | None,
    params: ScasParams | None,
    calibration: Calibration | None,
    surrogate: SurrogateModel | None,
    fleet_fields: dict[str, Any],
    obs_mode: str = "features+rul",
) -> tuple[FleetConfig, Setup]:
    """The fleet's configuration and its actuators' :class:`~scas_env.core.setup.Setup` from
    an env's keywords, each checked (``fleet_fields``: fields of :class:`FleetConfig`;
    ``obs_mode`` sets the actuators' scenario's: ``"state"`` shows each actuator's truth).
    The cheap checks come first: a bad argument raises before any calibration is built."""
    check_obs_mode(obs_mode)
    unread = sorted(set(fleet_fields) & {"mismatch", "world_surrogate"})
    if unread:
        raise ValueError(
            f"{unread} are keywords of the single env (ScasMaintenance-v2); the fleet's world "
            "is the monitor's model and takes none"
        )
    if fleet is not None and fleet_fields:
        raise ValueError(
            f"pass either fleet=FleetConfig(...) or its fields, not both: {sorted(fleet_fields)}"
        )
    for name, value, cls in (
        ("fleet", fleet, FleetConfig),
        ("scenario", scenario, Scenario),
        ("cost_model", cost_model, CostModel),
        ("params", params, ScasParams),
        ("calibration", calibration, Calibration),
        ("surrogate", surrogate, SurrogateModel),
    ):
        if value is not None and not isinstance(value, cls):
            raise ValueError(f"{name} = {value!r} must be None (the default) or a {cls.__name__}")
    default_value = CostModel().flight_value_usd
    if cost_model is not None and cost_model.flight_value_usd != default_value:
        raise ValueError(
            f"cost_model.flight_value_usd = {cost_model.flight_value_usd!r} is not read by the "
            f"fleet: a flight's value is its mission's, FleetConfig.mission_value_usd (per "
            f"mission type); leave flight_value_usd at its default {default_value!r}"
        )
    config = fleet if fleet is not None else FleetConfig.from_dict(fleet_fields)
    base = scenario if scenario is not None else Scenario(**FLEET_SCENARIO)
    wanted = "state" if obs_mode == "state" else "features+rul"
    if base.obs_mode not in (Scenario().obs_mode, wanted):
        raise ValueError(
            f"scenario.obs_mode = {base.obs_mode!r} is not read by the fleet: its view is set "
            f"by the env's obs_mode= keyword (one of 'features+rul', 'state', 'dict'; given "
            f"{obs_mode!r}); leave scenario.obs_mode at its default"
        )
    # the observation's bounds of ages and test age: at least the episode's flights
    slots = int(config.episode_days) * int(config.flights_per_mission)
    base = base.replace(
        episode_slots=max(int(base.episode_slots), slots),
        obs_mode=wanted,
    )
    params = params if params is not None else ScasParams()
    # before the calibration, which other params build in minutes
    surrogate = surrogate if surrogate is not None else shipped_surrogate_for(params)
    hours = params.mission.flight_duration_s / 3600.0
    if not math.isclose(config.demand.flight_hours_per_flight, hours, rel_tol=1e-9):
        raise ValueError(
            f"DemandModel.flight_hours_per_flight = {config.demand.flight_hours_per_flight!r} h "
            f"must equal the actuator's flight, MissionParams.flight_duration_s / 3600 = "
            f"{hours!r} h (flight hours and the damage per flight count the same flights)"
        )
    types = ("standard", *(t for t in config.mission_types if t != "standard"))
    setup = Setup(
        params=params,
        scenario=base,
        costs=cost_model if cost_model is not None else CostModel(),
        calibration=calibration if calibration is not None else env_calibration(params),
        surrogate=surrogate,
        mission_types=types,
    )
    return config, setup


def fleet_action_space(config: FleetConfig) -> spaces.MultiDiscrete:
    """Per aircraft: its mission choice (``1 + 2K``), then each actuator's maintenance
    choice (4), flattened aircraft by aircraft."""
    per = [1 + 2 * len(config.mission_types)] + [4] * int(config.actuators_per_aircraft)
    return spaces.MultiDiscrete(np.tile(per, int(config.aircraft)))


class ScasFleetEnv(gym.Env):
    """A fleet of helicopters with SCAS actuators, one crew, a pool of spares, day by day.

    ## Description

    ``N`` helicopters (default 8), each with ``A`` SCAS actuators (default 3: a three-axis
    SCAS), each actuator the single env's world with its two faults (a fatigue crack in a
    centering spring, piston-seal wear) and its monitor (features, two particle filters, RUL,
    risk). A step is a day. Each day brings missions (a demand model drawn at reset: base
    rate from the utilisation, seasonality, surges; types that differ in severity: their
    Table-1 regime mix changes each part's damage per flight, measured from whole simulated
    flights); a mission needs one free aircraft for ``F`` flights (default 2). One crew does
    ``C`` jobs a day (default 1), each with a spare from the pools (spring kits, seal kits,
    whole actuators from a rotable pool; base-stock replenishment with lead times). A part
    that fails in flight ends the mission and needs an unscheduled removal; a background
    removal (MTBUR 5,000 FH) that no feature sees takes an actuator to the shop. The task:
    fly the missions at the least cost. The dynamics of a day:
    :mod:`scas_env.core.fleet.batch`.

    ## Action Space

    ``MultiDiscrete`` of ``N (1 + A)`` entries, aircraft by aircraft:

    | entry | choices | meaning |
    |---|---|---|
    | mission | ``1 + 2K`` | 0 stand by; ``k = 1..K`` fly a mission of type ``k - 1``; |
    | | | ``K + k``: test every actuator before flight, then fly type ``k - 1`` |
    | actuator ``j`` | 4 | 0 nothing; 1 replace the spring; 2 replace the seals; 3 both |

    A maintenance choice queues crew jobs (each needs a crew job and a spare) and, unless the
    job is queued already, puts the aircraft in the hangar that day; the day the crew does a
    job the aircraft is in the hangar too, and further jobs on it that day cost no further
    downtime. While a
    preventive job waits for the crew or a spare an airworthy aircraft may fly. Missions go
    to the free aircraft asking for their type, in aircraft order, while any is left.
    :meth:`action_masks` (and ``info["action_mask"]``) gives the valid choices
    (MaskablePPO's format: the choices of every entry, concatenated): a mission type only
    for a free aircraft and a type asked tomorrow, plain flying not while a failed
    pre-flight test holds the aircraft (unless the scenario tests before every flight), a
    replacement only for a part that has flown.

    ## Observation Space

    ``Box`` (float32, documented bounds; ``env.unwrapped.obs_names`` names every entry and
    ``obs_units`` gives its unit: an actuator's slots are the fleet's days; the upper bounds
    of part ages and test age are ``max(scenario.episode_slots, the episode's flights)``, a
    bound on its days too; a part fitted before the episode and older than that reads as the
    bound until it is replaced), the
    groups of :mod:`scas_env.core.fleet.view`: per actuator the single env's 20 entries
    (latest features I2, I6, I7, I8, I9, G1, G3; test age; no-go; RUL mean, low quantile and
    risk of spring and seals; detector flags; part ages; downtime), per aircraft its status
    (jobs queued, broken, downtime, no-go, free), the fleet's spares on hand and on order, jobs
    waiting, the crew's jobs a day, the missions asked tomorrow and on the next
    ``lookahead_days`` days per type, the season and the days left. ``obs_mode="state"``
    shows each actuator's truth instead of its monitor (an oracle's view); ``"dict"`` the
    groups as a ``Dict``.

    ## Rewards

    Per day, in USD: each flight flown earns its mission type's value divided by ``F``; minus
    every actuator's tests, no-go inspections, replacements and in-flight failures
    (``CostModel``); minus the penalty of each mission not flown, the cost of each background
    removal and the spares' holding cost (``FleetConfig``). ``info["reward_terms"]`` splits
    it.

    ## Info

    The day, missions asked and flown, revenue; mission availability (missions flown /
    asked), aircraft availability (aircraft-days free / aircraft-days), flights, flight
    hours, cost and cost per FH, in-flight failures per part, background and unscheduled
    removals, replacements, tests, stock-outs per spare kind, jobs waiting and done,
    job-days waited, crew utilisation, wasted life, today's terms and each aircraft's share
    (``aircraft_reward``), the missions missed and assigned today, every actuator's true
    remaining life (flights of the standard mission), spares on hand and on order, the
    crew's books, the action mask. A part replaced after an in-flight failure is counted in
    ``replacements`` but not priced there: the failure's cost includes it.

    ## Rendering

    ``"ansi"``: one line of the day's KPIs (missions flown of those asked, failures, jobs
    waiting, cost); ``"rgb_array"``: the fleet's day drawn (:mod:`scas_env.fleet_dashboard`).

    ## Starting State

    Every actuator a new unit whose parts have flown a uniformly drawn fraction of their
    lives, their ages known and the monitor's filters predicted over them
    (``Scenario.initial_health = "in_service"`` unless a scenario is given), spares at their
    initial stock, no job queued, the whole episode's demand drawn.

    ## Episode End

    Truncation after ``episode_days`` days (default 365). No termination. The observation
    counts down to the end (``days_left``): for a learner it is terminal (no value past it).
    ``spec.max_episode_steps`` is None (the env truncates itself): read
    ``config.episode_days``.

    ## Arguments

    ``gym.make("scas_env/ScasFleet-v0", **kwargs)``, every keyword optional:

    * ``fleet``: a :class:`~scas_env.core.fleet.config.FleetConfig`, or its fields as
      keywords (``episode_days=30``; not both); a case file's ``[fleet]`` table:
      ``FleetConfig.load("examples/fleet_offshore.toml")`` (its ``[scenario]`` and
      ``[costs]`` tables: ``Scenario.load`` and ``CostModel.load`` of the same file);
    * ``scenario``: the actuators' :class:`~scas_env.core.scenario.Scenario` (default
      ``initial_health="in_service"``); its ``obs_mode`` stays at its default (the view is
      the keyword below), ``episode_slots`` is raised to the episode's flights;
    * ``cost_model``: tests, inspections, replacements and failures
      (:class:`~scas_env.core.costs.CostModel`); ``flight_value_usd`` stays at its default
      (a flight earns its mission's value);
    * ``params``, ``calibration``, ``surrogate``: the actuator model, its failure thresholds
      and its feature surrogate (defaults: the shipped ones);
    * ``obs_mode``: ``"features+rul"`` (default), ``"state"`` or ``"dict"`` (above);
    * ``render_mode``: ``None``, ``"ansi"`` (a line of the day's KPIs) or ``"rgb_array"``
      (the fleet's day drawn).

    The fleet's world is the monitor's model: it takes no ``mismatch`` (single env only).

    ## Version History

    * v0: initial release (0.2.0). Unreleased: every actuator of an aircraft flies the
      flight on which one of them fails (only those before it in the row order did);
      physics-fidelity fleets likewise. Episodes with an in-flight failure differ from that
      day on. With ``preflight="every_flight"`` the actuators test before each flight of a
      day, not once a day (a no-go grounds the aircraft for the rest of the day). Known
      defects kept until the next version (the rotable pool's repairs run one at a time,
      kit jobs outlive an actuator swap): docs/findings.md, "Known defects".

    ## Example

    >>> import gymnasium as gym
    >>> import scas_env
    >>> env = gym.make("scas_env/ScasFleet-v0", episode_days=30)
    >>> obs, info = env.reset(seed=0)
    >>> env.action_space.shape, obs.dtype
    ((32,), dtype('float32'))
    >>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    >>> info["day"]
    1
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["ansi", "rgb_array"], "render_fps": 4}

    def __init__(
        self,
        *,
        fleet: FleetConfig | None = None,
        scenario: Scenario | None = None,
        cost_model: CostModel | None = None,
        params: ScasParams | None = None,
        calibration: Calibration | None = None,
        surrogate: SurrogateModel | None = None,
        obs_mode: str = "features+rul",
        render_mode: str | None = None,
        **fleet_fields: Any,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode = {render_mode!r} must be None or one of "
                f"{self.metadata['render_modes']}"
            )
        self.render_mode = render_mode
        self.config, self.setup = make_fleet_setup(
            fleet, scenario, cost_model, params, calibration, surrogate, fleet_fields, obs_mode
        )
        self.fleet = FleetBatch(self.setup, self.config, 1)
        self.view = FleetView(self.fleet, obs_mode)
        self.observation_space = self.view.space
        self.action_space = fleet_action_space(self.config)
        self.obs_names, self.obs_units = self.view.names, self.view.units
        self._fleets = np.zeros(1, dtype=np.int64)
        self._actions = np.zeros(
            (1, int(self.config.aircraft), 1 + int(self.config.actuators_per_aircraft)),
            dtype=np.int64,
        )
        self._started = False

    # ------------------------------------------------------------------ gym API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        if seed is not None and (
            isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0
        ):
            raise ValueError(f"seed = {seed!r} must be None or an integer >= 0")
        if options is not None and (not isinstance(options, dict) or options):
            raise ValueError(f"options = {options!r}: this env takes no options (None or {{}})")
        super().reset(seed=None if seed is None else int(seed))
        self.fleet.reset(self._fleets, [self.np_random])
        self._started = True
        return self._outputs()

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        if self.fleet.day[0] >= self.fleet.shape.days:
            raise RuntimeError("the episode was truncated: call reset() before step()")
        self._actions[0] = check_fleet_action(action, self.action_space, self.config)
        with reset_needed_on_error(self):
            reward = float(self.fleet.step(self._fleets, self._actions)[0])
            truncated = bool(self.fleet.day[0] >= self.fleet.shape.days)
            obs, info = self._outputs()
        return obs, reward, False, truncated, info

    def _outputs(self) -> tuple[Any, dict[str, Any]]:
        values = self.view.groups(0)
        self._masks = self.view.masks(0, values)
        info = self.view.info(0, values)
        return self.view.observe(0, values), info

    def action_masks(self) -> np.ndarray:
        """Valid choices of every entry, concatenated (MaskablePPO's MultiDiscrete format)."""
        if not self._started:
            raise RuntimeError("call reset() before action_masks()")
        return self._masks.ravel()

    def render(self) -> str | np.ndarray | None:
        """``"ansi"``: the day in text; ``"rgb_array"``: the fleet drawn as an (H, W, 3)
        uint8 frame; no render mode: None. With a render mode, before :meth:`reset` (or
        after a step that raised) there is no day to draw: ``RuntimeError``, as the single
        env raises."""
        if self.render_mode is None:
            return None
        if not self._started:
            raise RuntimeError("call reset() before render()")
        if self.render_mode == "ansi":
            return render_text(self.view.info(0))
        if self.render_mode == "rgb_array":
            return draw_fleet(self.fleet, self.view, 0)
        return None


def check_fleet_action(
    action: Any, space: spaces.MultiDiscrete, config: FleetConfig, name: str = "action"
) -> np.ndarray:
    """``action`` as the (aircraft, 1 + A) int64 choices of ``space`` (a fleet's, or one
    aircraft's), or ``ValueError`` naming ``name``, the value and what is allowed: integers
    (no booleans, no floats), ``space.shape``, each entry within its choices."""
    n_act = int(config.actuators_per_aircraft)
    per = 1 + n_act
    n = int(space.shape[0])
    allowed = (
        f"{n} integers{', aircraft by aircraft' if n > per else ''}: a mission choice in "
        f"0..{int(space.nvec[0]) - 1} "
        f"then {n_act} maintenance choices in 0..3 {MAINTENANCE_CHOICES}"
    )
    if isinstance(action, list | tuple) and any(isinstance(v, bool | np.bool_) for v in action):
        raise ValueError(f"{name} = {action!r} holds a boolean; it must be {allowed}")
    try:
        arr = np.asarray(action)
    except (ValueError, TypeError):
        raise ValueError(f"{name} = {action!r} is not an array; it must be {allowed}") from None
    if arr.shape != space.shape:
        raise ValueError(f"{name} has shape {arr.shape} ({action!r}); it must be {allowed}")
    if arr.dtype.kind not in "iu":  # not timedelta64, which numpy counts as an integer
        raise ValueError(f"{name} has dtype {arr.dtype} ({action!r}); it must be {allowed}")
    bad = np.flatnonzero((arr < 0) | (arr >= space.nvec))
    if bad.size:
        k = int(bad[0])
        i, entry = divmod(k, per)
        what = "mission choice" if entry == 0 else f"actuator {entry - 1} maintenance choice"
        whose = f"aircraft {i}'s {what}" if n > per else what
        raise ValueError(
            f"{name}[{k}] = {int(arr[k])} ({whose}) must be in 0..{int(space.nvec[k]) - 1}; "
            f"{name} must be {allowed}"
        )
    return arr.astype(np.int64).reshape(-1, per)


__all__ = [
    "FLEET_SCENARIO",
    "ScasFleetEnv",
    "check_fleet_action",
    "fleet_action_space",
    "make_fleet_setup",
]
