"""The observation statistics of an agent, kept in a JSON file instead of a pickle.

The observation statistics of ``VecNormalize`` (a pickle, ``*_vecnormalize.pkl``) are kept
in a JSON file of this project, ``*_normalization.json`` (:class:`ObsNormalization`): the
running mean and variance of the observations (float64, exact), ``epsilon`` and
``clip_obs``, and for resuming training the return statistics. Its ``normalize_obs`` is
``VecNormalize.normalize_obs`` (the same arithmetic, bit for bit; tested).
:func:`convert_vecnormalize` converts a trusted pickle once. The agents' zips are read by
:mod:`policies.agents.agent_files`.

>>> norm = ObsNormalization(mean=[1.0, 2.0], var=[4.0, 1.0])
>>> norm.normalize_obs([3.0, 2.0]).tolist()
[1.0, 0.0]
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from policies.agents.agent_files import read_json_file

__all__ = ["NORMALIZATION_FORMAT", "ObsNormalization", "convert_vecnormalize"]

#: the ``format`` entry of a normalisation file (with ``version``)
NORMALIZATION_FORMAT = "scas-maintenance-gym/obs-normalization"
NORMALIZATION_VERSION = 1


def _finite_vector(path: Any, name: str, value: Any, size: int | None = None) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{path}: {name} must be a list of numbers") from None
    if arr.ndim != 1 or arr.size == 0 or (size is not None and arr.size != size):
        want = f"{size} numbers" if size is not None else "a non-empty list"
        raise ValueError(f"{path}: {name} has shape {arr.shape}; expected {want}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{path}: {name} holds non-finite values")
    return arr


def _finite_number(path: Any, name: str, value: Any, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{path}: {name} = {value!r} must be a number")
    x = float(value)
    if not math.isfinite(x) or x < 0.0 or (positive and x == 0.0):
        bound = "> 0" if positive else ">= 0"
        raise ValueError(f"{path}: {name} = {value!r} must be a finite number {bound}")
    return x


@dataclass(frozen=True, eq=False)
class ObsNormalization:
    """``VecNormalize``'s observation statistics (and, for resuming training, its return
    statistics) as plain numbers.

    Attributes
    ----------
    mean, var : running mean and variance of each observation entry (float64).
    epsilon : added to the variance before the square root.
    clip_obs : normalised observations are clipped to ``[-clip_obs, clip_obs]``.
    count : observations the statistics were accumulated from.
    returns : ``{"mean", "var", "count", "clip_reward", "gamma"}`` of the discounted
        returns (reward scaling while training), or ``None``.
    """

    mean: Any
    var: Any
    epsilon: float = 1e-8
    clip_obs: float = 10.0
    count: float = 0.0
    returns: Mapping[str, float] | None = field(default=None)

    def __post_init__(self) -> None:
        mean = _finite_vector("ObsNormalization", "mean", self.mean)
        var = _finite_vector("ObsNormalization", "var", self.var, mean.size)
        if (var < 0).any():
            raise ValueError("ObsNormalization: var holds negative values")
        for name, value, positive in (
            ("epsilon", self.epsilon, True),
            ("clip_obs", self.clip_obs, True),
            ("count", self.count, False),
        ):
            _finite_number("ObsNormalization", name, value, positive=positive)
        mean.flags.writeable = var.flags.writeable = False
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "var", var)
        if self.returns is not None:
            keys = ("mean", "var", "count", "clip_reward", "gamma")
            if set(self.returns) != set(keys):
                raise ValueError(f"ObsNormalization: returns must have exactly the keys {keys}")
            mean_r = self.returns["mean"]
            if (
                isinstance(mean_r, bool)
                or not isinstance(mean_r, int | float)
                or not (math.isfinite(mean_r))
            ):
                raise ValueError(f"ObsNormalization: returns.mean = {mean_r!r} must be finite")
            returns = {"mean": float(mean_r)}
            for k in keys[1:]:
                returns[k] = _finite_number("ObsNormalization", f"returns.{k}", self.returns[k])
            object.__setattr__(self, "returns", returns)

    @property
    def size(self) -> int:
        return int(self.mean.size)

    def normalize_obs(self, obs: Any) -> np.ndarray:
        """``VecNormalize.normalize_obs``: ``clip((obs - mean) / sqrt(var + epsilon))`` as
        float32 (the statistics are not updated)."""
        obs = np.asarray(obs)
        out = np.clip(
            (obs - self.mean) / np.sqrt(self.var + self.epsilon), -self.clip_obs, self.clip_obs
        )
        return out.astype(np.float32)

    # --- conversions ---------------------------------------------------------------------
    @classmethod
    def from_vecnormalize(cls, venv: Any) -> ObsNormalization:
        """The statistics of an SB3 ``VecNormalize`` (flat observations only)."""
        rms = venv.obs_rms
        if isinstance(rms, dict):
            raise ValueError("VecNormalize of dict observations: flatten the observation first")
        returns = None
        ret = getattr(venv, "ret_rms", None)
        if ret is not None:
            returns = {
                "mean": float(np.asarray(ret.mean).reshape(-1)[0]),
                "var": float(np.asarray(ret.var).reshape(-1)[0]),
                "count": float(ret.count),
                "clip_reward": float(venv.clip_reward),
                "gamma": float(venv.gamma),
            }
        if not venv.norm_obs:
            raise ValueError("VecNormalize with norm_obs=False: the agent acts on raw observations")
        return cls(
            mean=np.array(rms.mean, dtype=np.float64),
            var=np.array(rms.var, dtype=np.float64),
            epsilon=float(venv.epsilon),
            clip_obs=float(venv.clip_obs),
            count=float(rms.count),
            returns=returns,
        )

    def apply_to(self, venv: Any) -> None:
        """Set an SB3 ``VecNormalize``'s statistics to these (the return statistics too, when
        this file has them).

        Return statistics come with the reward scaling they were kept under: the discounted
        return of the file's ``gamma``, scaled rewards clipped at its ``clip_reward``. Both
        must equal the ``VecNormalize``'s, else ``ValueError`` names them before anything is
        set. They are checked, not set: they are settings the caller gave the
        ``VecNormalize`` (replacing them would change its training unseen), and statistics of
        another ``gamma`` are those of another return."""
        if venv.obs_rms.mean.shape != self.mean.shape:
            raise ValueError(
                f"the statistics are of {self.size} observation entries, the env's "
                f"{venv.obs_rms.mean.shape}"
            )
        if self.returns is not None:
            for key in ("gamma", "clip_reward"):
                if float(getattr(venv, key)) != self.returns[key]:
                    raise ValueError(
                        f"the return statistics are of {key} = {self.returns[key]!r}; the "
                        f"VecNormalize has {key} = {getattr(venv, key)!r} (make it with "
                        f"{key}={self.returns[key]!r})"
                    )
        venv.obs_rms.mean = self.mean.copy()
        venv.obs_rms.var = self.var.copy()
        venv.obs_rms.count = self.count
        venv.epsilon, venv.clip_obs = self.epsilon, self.clip_obs
        if self.returns is not None:
            venv.ret_rms.mean = np.float64(self.returns["mean"])
            venv.ret_rms.var = np.float64(self.returns["var"])
            venv.ret_rms.count = self.returns["count"]

    def to_json(self) -> dict[str, Any]:
        """The file's JSON document (floats written exactly: ``repr`` round-trips)."""
        return {
            "format": NORMALIZATION_FORMAT,
            "version": NORMALIZATION_VERSION,
            "obs_size": self.size,
            "mean": self.mean.tolist(),
            "var": self.var.tolist(),
            "epsilon": self.epsilon,
            "clip_obs": self.clip_obs,
            "count": self.count,
            "returns": None if self.returns is None else dict(self.returns),
        }

    def save(self, path: str | Path) -> Path:
        """Write the JSON file (atomically)."""
        from scas_env.utils.atomic_file import write_text_atomic

        path = Path(path)
        write_text_atomic(path, json.dumps(self.to_json(), indent=1) + "\n")
        return path

    @classmethod
    def load(cls, path: str | Path) -> ObsNormalization:
        """Read a file of :meth:`save`; anything else raises ``ValueError`` naming it."""
        path = Path(path)
        doc = read_json_file(path, "normalisation file")
        if not isinstance(doc, dict) or doc.get("format") != NORMALIZATION_FORMAT:
            raise ValueError(
                f'{path}: not a normalisation file (no "format": {NORMALIZATION_FORMAT!r})'
            )
        if doc.get("version") != NORMALIZATION_VERSION:
            raise ValueError(
                f"{path}: normalisation file version {doc.get('version')!r}; this package "
                f"reads version {NORMALIZATION_VERSION}"
            )
        allowed = {"format", "version", "obs_size", "mean", "var", "epsilon", "clip_obs",
                   "count", "returns"}  # fmt: skip
        unknown = sorted(set(doc) - allowed)
        if unknown:
            raise ValueError(f"{path}: unknown key(s) {unknown}; allowed: {sorted(allowed)}")
        size = doc.get("obs_size")
        if isinstance(size, bool) or not isinstance(size, int) or size < 1:
            raise ValueError(f"{path}: obs_size = {size!r} must be an integer >= 1")
        mean = _finite_vector(path, "mean", doc.get("mean"), size)
        var = _finite_vector(path, "var", doc.get("var"), size)
        try:
            return cls(
                mean=mean,
                var=var,
                epsilon=_finite_number(path, "epsilon", doc.get("epsilon"), positive=True),
                clip_obs=_finite_number(path, "clip_obs", doc.get("clip_obs"), positive=True),
                count=_finite_number(path, "count", doc.get("count", 0.0)),
                returns=doc.get("returns"),
            )
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{path}: {exc}") from None


def convert_vecnormalize(pkl: str | Path, out: str | Path | None = None) -> Path:
    """Convert a ``VecNormalize`` pickle into a normalisation JSON file (default: beside it,
    ``vecnormalize.pkl`` -> ``normalization.json``, ``<x>_vecnormalize.pkl`` ->
    ``<x>_normalization.json``). **Unpickles** ``pkl``: run it only on a file you trust;
    the JSON then loads without unpickling."""
    import pickle

    from stable_baselines3.common.vec_env import VecNormalize

    pkl = Path(pkl)
    if out is None:
        out = pkl.with_name(pkl.name.replace("vecnormalize", "normalization")).with_suffix(".json")
    with pkl.open("rb") as fh:
        venv = pickle.load(fh)  # trusted by the caller: this function's contract
    if not isinstance(venv, VecNormalize):
        raise ValueError(f"{pkl}: holds a {type(venv).__name__}, not VecNormalize")
    return ObsNormalization.from_vecnormalize(venv).save(out)
