"""Noisy oracle: the nested family acting on each part's life known up to a factor.

Positive and negative controls of the value-of-information ladder (:mod:`policies.value.study`):
the policy reads the true state (``obs_mode="state"``) and, for every part fitted, draws
one ``z ~ N(0, 1)`` from its own seeded generator; it then believes the part's life to be
``L_hat = (age + rul_true) * exp(sigma * z)`` (flights) and its RUL ``L_hat - age``. The
override of :class:`policies.rules.nested.NestedRule` replaces the part when that RUL is at most
its lead (``spring_lead`` / ``seal_lead``, flights; divided by ``scale`` while grounded).
``sigma = 0`` is a just-in-time oracle without planning; growing ``sigma`` must lower the
value (a control of the study).

The policy keeps one generator and one ``z`` per row (episode); it recognises a new part by
its age falling (a replacement or failure resets it to 0), and new parts at a row's
``episode_start`` (an env that resets itself: parts in service need not start younger).
``reset(seed=...)`` re-seeds: a sequence (or a 1-D integer array) of seeds gives one
generator per row, each drawing what a single episode with that seed draws, so batched and
single episodes agree (tested). A batch of ``n`` rows never seeded by row (SB3's
``evaluate_policy`` over ``n`` envs) draws row ``r`` from child ``r`` of
``SeedSequence(seed).spawn(n)``.

>>> names = ("crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true",
...          "spring_age", "seal_age", "downtime")
>>> p = NoisyOraclePolicy(names, sigma=0.0, spring_lead=5.0, seal_lead=5.0,
...                       spring_age=float("inf"), seal_age=float("inf"))
>>> p.reset(seed=0)
>>> p.predict([0.9, 0.1, 4.0, 900.0, 800.0, 100.0, 0.0])[0]  # spring within its lead
2
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from policies.base import IntArray, check_seed, episode_starts, register, row_seeds
from policies.rules.nested import NestedRule

__all__ = ["NoisyOraclePolicy"]


@register
class NoisyOraclePolicy(NestedRule):
    """Age backstop plus an override on a noisy true life (module docstring)."""

    name: ClassVar[str] = "noisy_oracle"
    obs_mode: ClassVar[str] = "state"
    family: ClassVar[str] = "bound"
    can_test: ClassVar[bool] = False
    reads: ClassVar[tuple[str, ...]] = (
        "spring_rul_true",
        "seal_rul_true",
        "spring_age",
        "seal_age",
        "downtime",
    )
    override_params: ClassVar[dict[str, float]] = {
        "sigma": 0.0,
        "spring_lead": 5.0,
        "seal_lead": 5.0,
        "seed": 0.0,
    }

    def __init__(self, obs_names: Sequence[str], **kwargs: Any) -> None:
        super().__init__(obs_names, **kwargs)
        self.base_seed = int(self.values["seed"])
        self.rngs: list[np.random.Generator] = [np.random.default_rng(self.base_seed)]
        self.z: np.ndarray | None = None
        self.last_age: np.ndarray | None = None

    def _check_value(self, name: str, value: float) -> float:
        if name == "seed" and (not math.isfinite(value) or value != int(value)):
            raise ValueError(f"seed = {value!r} must be an integer >= 0")
        if name == "sigma" and not math.isfinite(value):
            raise ValueError(f"sigma = {value!r} must be finite and >= 0")
        return super()._check_value(name, value)

    def reset(self, seed: int | Sequence[int] | None = None) -> None:
        """New episode(s): forget the parts' draws; re-seed when ``seed`` is given."""
        if seed is not None:
            rows = row_seeds(seed)
            seeds = [check_seed(seed)] if rows is None else rows
            self.rngs = [np.random.default_rng(int(s)) for s in seeds]
            if len(seeds) == 1:
                self.base_seed = int(seeds[0])
        self.z, self.last_age = None, None

    def _start_episodes(self, episode_start: Any) -> None:
        """Rows with ``episode_start`` set draw their parts' ``z`` anew (once: their ages are
        not compared with the last episode's)."""
        start = None if self.z is None else episode_starts(episode_start, self.z.shape[0])
        if start is not None and start.any():
            for k in range(2):
                self._draw(start, k)
            self.last_age[start] = -np.inf

    def _draw(self, rows: np.ndarray, part: int) -> None:
        for r in np.flatnonzero(rows):
            self.z[r, part] = self.rngs[r].standard_normal()

    def _override(self, obs: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = obs.shape[0]
        ages = np.stack([self.column(obs, "spring_age"), self.column(obs, "seal_age")], axis=1)
        if self.z is None:
            if len(self.rngs) == 1 and n > 1:  # a batch never seeded by row (SB3's
                # evaluate_policy over n envs): row r draws from child r of the seed
                children = np.random.SeedSequence(self.base_seed).spawn(n)
                self.rngs = [np.random.default_rng(c) for c in children]
            if len(self.rngs) != n:
                raise ValueError(
                    f"{n} observations for {len(self.rngs)} seeded rows: call "
                    "reset(seed=[one seed per row]) first"
                )
            self.z = np.zeros((n, 2))
            for k in range(2):
                self._draw(np.ones(n, dtype=bool), k)
        elif self.z.shape[0] != n:
            raise ValueError(f"{n} observations for {self.z.shape[0]} rows of this episode")
        else:
            for k in range(2):
                self._draw(ages[:, k] < self.last_age[:, k], k)
        self.last_age = ages.copy()
        sigma = self.values["sigma"]
        out = []
        for k, part in enumerate(("spring", "seal")):
            rul = self.column(obs, f"{part}_rul_true")
            life = (ages[:, k] + rul) * np.exp(sigma * self.z[:, k])
            out.append((life - ages[:, k]) * scale <= self.values[f"{part}_lead"])
        return out[0], out[1]

    def _act(self, obs: np.ndarray) -> IntArray:
        if not self.override:  # keep the draws in step even when the override is off
            self._override(obs, np.ones(obs.shape[0]))
        return super()._act(obs)
