"""Fleet rules as operators run them, and the references, for ``ScasFleet-v0``.

Every rule reads the fleet's flat observation by name (``env.unwrapped.obs_names``) and
answers the project's policy protocol with the fleet's action (per aircraft its mission
choice, then each actuator's maintenance choice). A part ``p`` of an actuator is **due**
when it has flown (age > 0) and

* its age passes the backstop ``scale * T_p`` (flights), or
* (the filter rules) its risk of failing within the horizon passes ``scale * r``, or its
  low RUL quantile ``* scale`` falls to its lead ``L_p`` (flights), or
* a failed pre-flight test implicates it (:func:`policies.rules.healthy_band.implicated_spring`),

with ``scale = 1``, or ``1 - opportunity`` for the opportunistic grouping on an aircraft that
is in the hangar anyway. An aircraft with a due part does not fly: it asks for its due parts
(and waits on the ground while their jobs wait for a spare or the crew); the other free
aircraft ask for tomorrow's missions (the pre-flight test when an actuator's last test is
``test_every`` slots old). The families:

* ``fleet_corrective``: no preventive replacement (run to failure, repairs only);
* ``fleet_age``: the age backstops only (the age rule per part), opportunistic grouping;
* ``fleet_naive``: each part's filter rule (backstop, risk, lead, tests), no grouping,
  missions to the free aircraft in a fixed order (aircraft 0 first, types in the config's
  order); crew first come first served and base-stock spares are the env's;
* ``fleet_opportunistic``: the naive rule plus grouping: an aircraft in the hangar also has
  its parts within ``opportunity`` of their thresholds replaced;
* ``fleet_aware``: the opportunistic rule plus fleet-aware scheduling: the healthiest free
  aircraft (lowest risk) fly the most damaging mission types; a replacement that is not
  urgent (risk below ``urgency * r``, RUL low quantile above ``L_p / urgency``, age below the
  backstop, no failed test) waits for a day when the fleet has a free aircraft beyond
  tomorrow's demand (``urgency = 1``: every due part is urgent, no deferral);
* ``fleet_oracle`` (bound, ``obs_mode="state"``): each part replaced when its true remaining
  life (standard flights, known) falls to ``lead_flights`` (a damaging mission uses up to
  ~3 standard flights' worth per flight), grouped in the hangar;
* ``fleet_random`` (bound): random choices among the valid ones (the same masks as the
  env's), seeded per episode.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from policies.base import check_finite, check_seed, register_policy, row_seeds
from policies.rules.healthy_band import implicated_spring
from prognostics.validation import real

#: the families of this module, in the benchmark's order
FLEET_FAMILIES = (
    "fleet_corrective",
    "fleet_age",
    "fleet_naive",
    "fleet_opportunistic",
    "fleet_aware",
    "fleet_oracle",
    "fleet_random",
)
PARTS = ("spring", "seal")
#: the families' defaults, tuned on training fleets (seeds disjoint from the benchmark's):
#: ``scas-tune --fleet --trials 30 --episodes 16 --workers 2 --out
#: results/fleet_tuning`` (one Optuna budget per family, nested: naive -> opportunistic ->
#: aware; 480 training episodes each; 4 significant digits). Measured, not imposed: the
#: aware rule's deferral tunes to off (``urgency`` 1, its start), the filter rules'
#: ``test_every`` beyond the 365-day episode (no scheduled test is made) and the grouping
#: to a tenth of a threshold.
_OPPORTUNISTIC = {
    "spring_age": 1537.0,
    "seal_age": 4435.0,
    "test_every": 4526.0,
    "risk_threshold": 0.1008,
    "spring_lead": 5.057,
    "seal_lead": 0.5897,
    "opportunity": 0.1059,
}
FLEET_TUNED: dict[str, dict[str, float]] = {
    "fleet_age": {"spring_age": 999.5, "seal_age": 2283.0, "opportunity": 0.7234},
    "fleet_naive": {
        "spring_age": 2582.0,
        "seal_age": 5761.0,
        "test_every": 1167.0,
        "risk_threshold": 0.09076,
        "spring_lead": 2.102,
        "seal_lead": 0.9441,
    },
    "fleet_opportunistic": _OPPORTUNISTIC,
    # its best trial is its start: the opportunistic rule's best, urgency 1
    "fleet_aware": {**_OPPORTUNISTIC, "urgency": 1.0},
    "fleet_oracle": {"lead_flights": 10.05, "opportunity": 0.06485},
}


class FleetLayout:
    """Column indices of a fleet observation, from its names (``FleetView.names``)."""

    def __init__(self, obs_names: Sequence[str]) -> None:
        names = [str(n) for n in obs_names]
        index = {n: k for k, n in enumerate(names)}
        aircraft = sorted(
            {int(n.split(".")[0].split("_")[1]) for n in names if n.startswith("aircraft_")}
        )
        if not aircraft:
            raise ValueError("obs_names hold no 'aircraft_<i>.' entries: not a fleet observation")
        actuators = sorted({int(n.split(".")[1].split("_")[1]) for n in names if ".actuator_" in n})
        self.n, self.a = len(aircraft), len(actuators)
        self.types = tuple(n.split(".", 1)[1] for n in names if n.startswith("demand_day0."))
        self.k = len(self.types)
        self._index, self._names = index, names

    def actuator_cols(self, field: str) -> np.ndarray:
        """(N, A) columns of ``field`` of every actuator."""
        return np.array(
            [[self._col(f"aircraft_{i}.actuator_{j}.{field}") for j in range(self.a)]
             for i in range(self.n)]
        )  # fmt: skip

    def aircraft_cols(self, field: str) -> np.ndarray:
        return np.array([self._col(f"aircraft_{i}.{field}") for i in range(self.n)])

    def demand_cols(self) -> np.ndarray:
        return np.array([self._col(f"demand_day0.{t}") for t in self.types])

    def has(self, field: str) -> bool:
        return f"aircraft_0.actuator_0.{field}" in self._index

    def _col(self, name: str) -> int:
        if name not in self._index:
            raise ValueError(f"the fleet observation has no entry {name!r}")
        return self._index[name]


def _positive(name: str, value: float) -> float:
    v = float(value)
    if not v > 0.0 or math.isnan(v):
        raise ValueError(f"{name} = {value!r} must be > 0 (inf allowed)")
    return v


class FleetRule:
    """A fleet rule of one family (module docstring); ``params`` override its defaults."""

    #: per family: (policy family, obs_mode, defaults, uses the filters, groups, aware)
    FAMILIES: ClassVar[dict[str, tuple[str, str, dict[str, float], bool, bool, bool]]] = {
        "fleet_corrective": ("rule", "features+rul", {}, False, False, False),
        "fleet_age": ("rule", "features+rul", FLEET_TUNED["fleet_age"], False, True, False),
        "fleet_naive": ("rule", "features+rul", FLEET_TUNED["fleet_naive"], True, False, False),
        "fleet_opportunistic": ("rule", "features+rul", FLEET_TUNED["fleet_opportunistic"],
                                True, True, False),
        "fleet_aware": ("rule", "features+rul", FLEET_TUNED["fleet_aware"], True, True, True),
        "fleet_oracle": ("bound", "state", FLEET_TUNED["fleet_oracle"], False, True, False),
    }  # fmt: skip

    def __init__(self, family: str, obs_names: Sequence[str], **params: float) -> None:
        if family not in self.FAMILIES:
            raise ValueError(f"family = {family!r} must be one of {sorted(self.FAMILIES)}")
        self.name = family
        _, _, defaults, self.filters, self.groups, self.aware = self.FAMILIES[family]
        unknown = sorted(set(params) - set(defaults))
        if unknown:
            raise ValueError(
                f"unknown parameters {unknown} of {family!r}; it takes {sorted(defaults)}"
            )
        self.values = {**defaults, **{k: real(k, v, finite=False) for k, v in params.items()}}
        for k, v in self.values.items():
            if k == "opportunity" and not 0.0 <= v < 1.0:
                raise ValueError(f"opportunity = {v!r} must be in [0, 1)")
            if k == "risk_threshold" and not 0.0 < v <= 1.0:
                raise ValueError(f"risk_threshold = {v!r} must be in (0, 1]")
            if k not in ("opportunity", "risk_threshold"):
                _positive(k, v)
        self.layout = lay = FleetLayout(obs_names)
        self.obs_names = tuple(obs_names)
        self._age = {p: lay.actuator_cols(f"{p}_age") for p in PARTS}
        self._free = lay.aircraft_cols("free")
        self._jobs = lay.aircraft_cols("jobs_queued")
        self._broken = lay.aircraft_cols("broken")
        self._demand = lay.demand_cols()
        if family == "fleet_oracle":
            self._life = {p: lay.actuator_cols(f"{p}_rul_true") for p in PARTS}
        else:
            self._risk = {p: lay.actuator_cols(f"{p}_risk") for p in PARTS}
            self._low = {p: lay.actuator_cols(f"{p}_rul_low") for p in PARTS}
            self._test_age = lay.actuator_cols("test_age")
            self._no_go = lay.actuator_cols("no_go")
            self._g = {f: lay.actuator_cols(f) for f in ("G1", "G3")}
        self._severity = _type_severity(lay.types) if self.aware else None

    def params(self) -> dict[str, float]:
        return dict(self.values)

    def reset(self, seed: Any = None) -> None:
        """Rules keep no state."""

    # ------------------------------------------------------------------ the rule
    def _due(self, obs: np.ndarray, scale: np.ndarray) -> dict[str, np.ndarray]:
        """Per part, (B, N, A) whether it is due at ``scale`` (B, N, 1)."""
        v, out = self.values, {}
        for p in PARTS:
            age = obs[:, self._age[p]]
            due = np.zeros(age.shape, dtype=bool)
            if f"{p}_age" in v:
                due |= age >= scale * v[f"{p}_age"]
            if self.name == "fleet_oracle":
                due |= obs[:, self._life[p]] * scale <= v["lead_flights"]
            elif self.filters:
                due |= obs[:, self._risk[p]] >= scale * v["risk_threshold"]
                due |= obs[:, self._low[p]] * scale <= v[f"{p}_lead"]
            out[p] = due
        if self.filters:
            failed = obs[:, self._no_go] > 0.5
            spring = implicated_spring(obs[:, self._g["G1"]], obs[:, self._g["G3"]])
            out["spring"] |= failed & spring
            out["seal"] |= failed & ~spring
        for p in PARTS:  # a part that has not flown is never replaced (the env's mask)
            out[p] &= obs[:, self._age[p]] > 0
        return out

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:  # fmt: skip
        obs = np.asarray(observation, dtype=np.float64)
        single = obs.ndim == 1
        obs = np.atleast_2d(obs)
        if obs.shape[1] != len(self.obs_names):
            raise ValueError(
                f"observation has shape {obs.shape}; expected (B, {len(self.obs_names)})"
            )
        check_finite(obs if not single else obs[0], self.obs_names)
        lay = self.layout
        b = obs.shape[0]
        ones = np.ones((b, lay.n, 1))
        due = self._due(obs, ones)
        needs = (due["spring"] | due["seal"]).any(axis=2)
        # on the ground: broken, or jobs of its own queued for a spare or the crew (asked to
        # fly meanwhile, it would be pulled into the hangar when the job starts)
        in_hangar = (obs[:, self._broken] > 0) | (obs[:, self._jobs] > 0)
        free = obs[:, self._free] > 0.5
        demand = obs[:, self._demand].astype(np.int64)
        if self.aware:
            needs = self._defer(obs, due, needs, free & ~in_hangar, demand)
        hangar = needs | in_hangar
        if self.groups and "opportunity" in self.values:
            relaxed = self._due(
                obs, np.where(hangar, 1.0 - self.values["opportunity"], 1.0)[..., None]
            )
            due = {p: due[p] | (relaxed[p] & hangar[..., None]) for p in PARTS}
        due = {p: due[p] & hangar[..., None] for p in PARTS}
        act = np.zeros((b, lay.n, 1 + lay.a), dtype=np.int64)
        act[:, :, 1:] = due["spring"] * 1 + due["seal"] * 2
        flying = free & ~hangar
        test = np.zeros_like(flying)
        if self.filters and math.isfinite(self.values.get("test_every", math.inf)):
            test = (obs[:, self._test_age] >= self.values["test_every"]).any(axis=2)
        act[:, :, 0] = self._missions(obs, flying, demand, test)
        out = act.reshape(b, -1)
        return (out[0] if single else out), state

    def _missions(
        self, obs: np.ndarray, flying: np.ndarray, demand: np.ndarray, test: np.ndarray
    ) -> np.ndarray:
        """Mission choices (B, N): free aircraft ask for tomorrow's types (module doc)."""
        lay = self.layout
        choice = np.zeros(flying.shape, dtype=np.int64)
        for b in range(flying.shape[0]):
            order = np.flatnonzero(flying[b])
            types = list(range(lay.k))
            if self.aware:
                health = self._health(obs[b])[order]
                order = order[np.argsort(health, kind="stable")]
                types = sorted(types, key=lambda k: -self._severity[k])
            left = demand[b].copy()
            for i in order.tolist():
                k = next((k for k in types if left[k] > 0), None)
                if k is None:
                    break
                left[k] -= 1
                choice[b, i] = 1 + k + (lay.k if test[b, i] else 0)
        return choice

    def _health(self, obs: np.ndarray) -> np.ndarray:
        """(N,) the largest risk of an aircraft's parts (lower: healthier)."""
        return np.maximum(obs[self._risk["spring"]], obs[self._risk["seal"]]).max(axis=1)

    def _defer(
        self, obs: np.ndarray, due: dict[str, np.ndarray], needs: np.ndarray, free: np.ndarray,
        demand: np.ndarray,
    ) -> np.ndarray:  # fmt: skip
        """Non-urgent replacements wait for a day with a free aircraft to spare: of the
        ``free`` aircraft (not on the ground) that the urgent ones leave, those beyond
        tomorrow's demand may go, riskiest first."""
        v = self.values
        u = v["urgency"]
        urgent = np.zeros(needs.shape, dtype=bool)
        for p in PARTS:
            hot = obs[:, self._risk[p]] >= u * v["risk_threshold"]
            short = obs[:, self._low[p]] <= v[f"{p}_lead"] / u
            old = obs[:, self._age[p]] >= v[f"{p}_age"]
            urgent |= (due[p] & (hot | short | old)).any(axis=2)
        failed = (obs[:, self._no_go] > 0.5).any(axis=2)
        must = needs & (urgent | failed)
        deferred = needs & ~must
        slack = (free & ~must).sum(axis=1) - demand.sum(axis=1)
        go = must | (deferred & ~free)  # on the ground anyway: no spare aircraft used
        for b in np.flatnonzero((slack > 0) & (deferred & free).any(axis=1)):
            waiting = np.flatnonzero(deferred[b] & free[b])
            riskiest = waiting[np.argsort(-self._health(obs[b])[waiting], kind="stable")]
            go[b, riskiest[: slack[b]]] = True
        return go


def _type_severity(types: Sequence[str]) -> list[float]:
    """A mission type's damage per flight relative to the standard one: the mean of its
    crack multiplier over the growth grid and its wear multiplier (the shipped table)."""
    from scas_env.actuator.mission_damage import default_mission_damage

    table = default_mission_damage()
    out = []
    for t in types:
        row = table.types[t]
        out.append(0.5 * (float(np.mean(row.crack_multiplier)) + float(row.wear_multiplier)))
    return out


class FleetRandom:
    """Random valid choices (``fleet_random``): a free aircraft asks with probability
    ``p_fly`` for one of the types asked tomorrow (uniform among them; none asked: it stands
    by), tests with ``p_test`` (always when a failed test holds it); each flown part is
    replaced with probability ``p_replace`` a day: every choice one the env's mask allows.
    One generator per episode (``reset(seed=...)``, a seed per row of the batch as a list,
    tuple or 1-D integer array, or one seed whose stream serves every row in turn;
    ``reset()`` keeps the current ones)."""

    name = "fleet_random"

    def __init__(
        self, obs_names: Sequence[str], p_fly: float = 0.9, p_test: float = 0.05,
        p_replace: float = 0.002,
    ) -> None:  # fmt: skip
        given = {"p_fly": p_fly, "p_test": p_test, "p_replace": p_replace}
        for k, v in given.items():
            if not 0.0 <= real(k, v, finite=False) <= 1.0:
                raise ValueError(f"{k} = {v!r} must be a probability in [0, 1]")
        self.p = (float(p_fly), float(p_test), float(p_replace))
        self.layout = lay = FleetLayout(obs_names)
        self.obs_names = tuple(obs_names)
        self._free = lay.aircraft_cols("free")
        self._held = lay.aircraft_cols("no_go")
        self._asked = lay.demand_cols()
        self._age = {p: lay.actuator_cols(f"{p}_age") for p in PARTS}
        self._rngs = [np.random.default_rng(0)]

    def params(self) -> dict[str, float]:
        return {"p_fly": self.p[0], "p_test": self.p[1], "p_replace": self.p[2]}

    def reset(self, seed: Any = None) -> None:
        if seed is None:  # the protocol's reset between episodes: the streams go on
            return
        rows = row_seeds(seed)
        seeds = [check_seed(seed)] if rows is None else rows
        self._rngs = [np.random.default_rng(s) for s in seeds]

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:  # fmt: skip
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        if obs.ndim != 2 or obs.shape[1] != len(self.obs_names):
            raise ValueError(
                f"observation has shape {obs.shape}; expected (B, {len(self.obs_names)})"
            )
        check_finite(obs if np.ndim(observation) != 1 else obs[0], self.obs_names)
        if len(self._rngs) not in (1, obs.shape[0]):
            raise ValueError(
                f"{obs.shape[0]} observations for {len(self._rngs)} seeded rows: reset(seed=...) "
                "with one seed per row (or one seed, one stream for the whole batch)"
            )
        lay = self.layout
        out = np.zeros((obs.shape[0], lay.n, 1 + lay.a), dtype=np.int64)
        for b in range(obs.shape[0]):
            rng = self._rngs[b % len(self._rngs)]
            u = rng.random((lay.n, 3 + 2 * lay.a))
            asked = np.flatnonzero(obs[b, self._asked] > 0)
            fly = (obs[b, self._free] > 0.5) & (u[:, 0] < self.p[0]) & (asked.size > 0)
            kind = asked[(u[:, 1] * asked.size).astype(np.int64)] if asked.size else 0
            test = (u[:, 2] < self.p[1]) | (obs[b, self._held] > 0.5)
            out[b, :, 0] = np.where(fly, 1 + kind + lay.k * test, 0)
            rep = u[:, 3:].reshape(lay.n, lay.a, 2) < self.p[2]
            rep &= np.stack([obs[b, self._age[p]] > 0 for p in PARTS], axis=-1)
            out[b, :, 1:] = rep[..., 0] * 1 + rep[..., 1] * 2
        flat = out.reshape(obs.shape[0], -1)
        return (flat[0] if np.ndim(observation) == 1 else flat), state


for _family, (_kind, _mode, *_rest) in FleetRule.FAMILIES.items():
    register_policy(
        _family,
        lambda obs_names, _f=_family, **params: FleetRule(_f, obs_names, **params),
        obs_mode=_mode,
        family=_kind,
    )
register_policy("fleet_random", FleetRandom, obs_mode="features+rul", family="bound")

__all__ = ["FLEET_FAMILIES", "FleetLayout", "FleetRandom", "FleetRule"]
