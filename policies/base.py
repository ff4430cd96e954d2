"""The policy protocol of the benchmark and a registry of policies by name.

Every policy answers ``predict(observation, state=None, episode_start=None,
deterministic=True) -> (action, state)`` like a stable-baselines3 model, so SB3's
``evaluate_policy`` and the benchmark drive rules, the oracle and trained agents alike.
Policies read observation entries **by name**: they take the env's ``obs_names``
(``env.unwrapped.obs_names``) at construction and look their columns up once, so one rule
runs on any flat observation layout that holds the entries it reads (``"dict"``
observations are not supported: flatten them first).

>>> names = ("spring_age", "seal_age", "downtime")
>>> policy = make_policy("corrective", names)
>>> policy.predict([10.0, 20.0, 0.0])
(0, None)
>>> actions, _ = policy.predict([[10.0, 20.0, 0.0], [5.0, 5.0, 1.0]])
>>> actions.tolist()
[0, 0]
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from typing import Any, ClassVar

import numpy as np

from scas_env.env import FLY, REPLACE_SEAL, REPLACE_SPRING, TEST_AND_FLY

IntArray = np.ndarray

#: Policy families: ``"rule"`` (condition-based rules), ``"bound"`` (oracle, random),
#: ``"external"`` (anything registered from outside, e.g. a trained agent).
FAMILIES = ("rule", "bound", "external")

__all__ = [
    "FAMILIES",
    "FLY",
    "POLICIES",
    "REPLACE_SEAL",
    "REPLACE_SPRING",
    "SEEDS_ALLOWED",
    "TEST_AND_FLY",
    "Policy",
    "check_finite",
    "check_seed",
    "episode_starts",
    "make_policy",
    "policy_family",
    "policy_obs_mode",
    "register_policy",
    "row_seeds",
]


def episode_starts(episode_start: Any, rows: int) -> np.ndarray | None:
    """SB3's ``episode_start`` as one bool per row of a batch of ``rows`` (a single flag
    for every row); None if not given. Raises ``ValueError`` for any other length."""
    if episode_start is None:
        return None
    start = np.atleast_1d(np.asarray(episode_start, dtype=bool))
    if start.size == 1:
        return np.full(rows, bool(start.reshape(-1)[0]))
    if start.shape != (rows,):
        raise ValueError(
            f"episode_start has shape {start.shape} for a batch of {rows} rows: give one "
            f"flag, or one per row ({rows},)"
        )
    return start


#: what ``reset(seed=...)`` of the project's policies takes
SEEDS_ALLOWED = "None, an integer >= 0 or a non-empty sequence of them (one per row)"


def _entry_seed(batch: Any, seed: Any) -> int:
    """One entry of a batch of seeds (:func:`check_seed`), the batch named if it is bad."""
    try:
        return check_seed(seed)
    except ValueError:
        raise ValueError(f"seed = {batch!r}: its entry {seed!r} is not an integer >= 0") from None


def check_seed(seed: Any) -> int:
    """A policy's seed as an ``int``: an integer >= 0 (a numpy integer too), else
    ``ValueError`` naming it (a float, a bool, a string is not silently turned into one)."""
    if isinstance(seed, np.ndarray) and seed.ndim == 0:
        seed = seed[()]
    if isinstance(seed, bool | np.bool_) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed = {seed!r} must be {SEEDS_ALLOWED}")
    return int(seed)


def row_seeds(seed: Any) -> list[int] | None:
    """The per-row seeds of ``reset(seed=...)``: a sequence (list, tuple) or a 1-D integer
    numpy array gives one seed per row (each :func:`check_seed`-ed); None for a single seed
    (an int, a 0-d array). Raises ``ValueError`` for another array or a bad entry."""
    if isinstance(seed, np.ndarray):
        if seed.ndim == 0:
            return None
        if seed.ndim != 1 or not np.issubdtype(seed.dtype, np.integer):
            raise ValueError(
                f"seed = {seed!r}: an array of seeds must be 1-D of integers (one per row), "
                f"got shape {seed.shape} and dtype {seed.dtype}"
            )
        return [_entry_seed(seed, s) for s in seed]
    if isinstance(seed, Sequence) and not isinstance(seed, str | bytes):
        return [_entry_seed(seed, s) for s in seed]
    return None


def check_finite(obs: np.ndarray, names: Sequence[str]) -> None:
    """Raise ``ValueError`` naming the non-finite (NaN, inf) entries of an observation or a
    batch (2-D, one row per env) by row, index and name (rules and agents alike): the env's
    observations are finite (every entry saturates at finite bounds), and a policy would
    act on a NaN as on a small value."""
    bad = ~np.isfinite(obs)
    if not bad.any():
        return
    rows, cols = np.nonzero(np.atleast_2d(bad))
    values = np.atleast_2d(obs)[rows, cols]
    where = [
        ("" if obs.ndim == 1 else f"row {r} ") + f"[{c}] {names[c]!r} = {v!r}"
        for r, c, v in zip(rows.tolist(), cols.tolist(), values.tolist(), strict=True)
    ]
    more = f" and {len(where) - 5} more" if len(where) > 5 else ""
    raise ValueError(
        f"observation has non-finite entries ({', '.join(where[:5])}{more}): every entry "
        "must be a finite number"
    )


class Policy(ABC):
    """Base class of the benchmark's policies (stateless rules on the current observation).

    Class attributes
    ----------------
    name : registry name.
    obs_mode : the ``Scenario.obs_mode`` the policy is meant to run with (the benchmark
        builds its env with it).
    family : one of :data:`FAMILIES`.
    reads : observation entries the policy reads; construction raises ``ValueError`` when
        ``obs_names`` lacks one.
    """

    name: ClassVar[str]
    obs_mode: ClassVar[str]
    family: ClassVar[str] = "rule"
    reads: ClassVar[tuple[str, ...]] = ()

    def __init__(self, obs_names: Sequence[str]) -> None:
        names = tuple(str(n) for n in obs_names)
        missing = [n for n in self.reads if n not in names]
        if missing:
            raise ValueError(
                f"obs_names lack {missing} that policy {self.name!r} reads; got {names} "
                f"(run it with obs_mode={self.obs_mode!r})"
            )
        self.obs_names = names
        self._col = {n: names.index(n) for n in self.reads}

    # ------------------------------------------------------------------ protocol
    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[int | IntArray, Any]:
        """Action(s) for one observation (returns an ``int``) or a batch (one row per env,
        returns an ``int64`` array); ``state`` is passed through (SB3 convention).
        ``ValueError`` for a non-finite entry (:func:`check_finite`) or an
        ``episode_start`` that is neither one flag nor one per row."""
        obs = np.asarray(observation, dtype=np.float64)
        if obs.ndim not in (1, 2) or obs.shape[-1] != len(self.obs_names):
            raise ValueError(
                f"observation has shape {obs.shape}; expected ({len(self.obs_names)},) or "
                f"(n_envs, {len(self.obs_names)}) for obs_names {self.obs_names}"
            )
        check_finite(obs, self.obs_names)
        if episode_start is not None:
            rows = 1 if obs.ndim == 1 else obs.shape[0]
            episode_starts(episode_start, rows)  # one flag or one per row, else ValueError
            self._start_episodes(episode_start)
        actions = self._act(np.atleast_2d(obs)).astype(np.int64)
        return (int(actions[0]) if obs.ndim == 1 else actions), state

    def _start_episodes(self, episode_start: Any) -> None:  # noqa: B027
        """SB3's ``episode_start`` of a :meth:`predict` call (:func:`episode_starts` reads it
        per row): the rows set begin an episode. Rules keep no state; a policy that keeps
        per-episode state starts it over here."""

    def reset(self, seed: int | Sequence[int] | None = None) -> None:  # noqa: B027
        """Start a new episode, or a batch of episodes side by side (a sequence of seeds, or
        a 1-D integer array, one per row: :func:`row_seeds`); rules keep no state, random
        policies re-seed."""

    def params(self) -> dict[str, Any]:
        """The policy's parameters (for tables and for rebuilding it by name)."""
        return {}

    def column(self, obs: np.ndarray, name: str) -> np.ndarray:
        """Column ``name`` of a 2-D observation batch."""
        return obs[:, self._col[name]]

    @abstractmethod
    def _act(self, obs: np.ndarray) -> IntArray:
        """Actions (n,) for observations (n, len(obs_names)), float64."""

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.params().items())
        return f"{type(self).__name__}({args})"


PolicyFactory = Callable[..., Any]
#: name -> factory ``(obs_names, **params) -> object with predict``.
POLICIES: dict[str, PolicyFactory] = {}
_META: dict[str, tuple[str, str]] = {}


def register_policy(
    name: str, factory: PolicyFactory, *, obs_mode: str, family: str = "external"
) -> None:
    """Register ``factory(obs_names, **params)`` under ``name`` (e.g. a loader of an SB3
    model: any object with ``predict(obs, state, episode_start, deterministic)`` works)."""
    if family not in FAMILIES:
        raise ValueError(f"family = {family!r} must be one of {FAMILIES}")
    POLICIES[name] = factory
    _META[name] = (obs_mode, family)


def register(cls: type[Policy]) -> type[Policy]:
    """Class decorator: register a :class:`Policy` subclass under its ``name``."""
    register_policy(cls.name, cls, obs_mode=cls.obs_mode, family=cls.family)
    return cls


def _known(name: str) -> None:
    if name not in POLICIES:
        raise ValueError(f"policy = {name!r} is not registered; known: {sorted(POLICIES)}")


def make_policy(name: str, obs_names: Sequence[str], **params: Any) -> Any:
    """Build the policy registered as ``name`` for an env with ``obs_names``."""
    _known(name)
    return POLICIES[name](obs_names, **params)


def policy_obs_mode(name: str) -> str:
    """``obs_mode`` the policy registered as ``name`` runs with."""
    _known(name)
    return _META[name][0]


def policy_family(name: str) -> str:
    """Family (:data:`FAMILIES`) of the policy registered as ``name``."""
    _known(name)
    return _META[name][1]
