"""The monitor's risk outputs through fitted recalibration maps: a wrapper and its file.

The observation's ``spring_risk`` and ``seal_risk`` are each filter's ``P(fail within
Scenario.risk_horizon_flights)``. :func:`recalibrate_risk` wraps a single env or the native
vector env (:class:`gymnasium.wrappers.TransformObservation` and its vector form) so that
they pass through :class:`prognostics.metrics.RiskMap` s fitted on training lives
(``python -m experiments.risk_recalibration``; docs/beliefs.md, "Recalibrated risk"): every
other entry, the action space, the rewards and ``info`` (whose beliefs stay the filters')
are unchanged, the mapped risk is cast to float32 as the observation is. A map belongs to
the monitor and the world it was fitted on: :func:`load_risk_maps` reads a file written by
:func:`save_risk_maps` and :func:`recalibrate_risk` refuses an env whose scenario or
parameters differ from the file's, except in :data:`FREE_FIELDS` (fields that change
neither what the filters believe nor how the parts live).

    >>> import gymnasium as gym
    >>> from prognostics.metrics import RiskMap
    >>> env = gym.make("scas_env/ScasMaintenance-v2")
    >>> maps = {"spring": RiskMap((0.0, 1.0), (0.5, 1.0))}
    >>> wrapped = recalibrate_risk(env, maps)
    >>> obs, _ = wrapped.reset(seed=0)
    >>> k = env.unwrapped.obs_names.index("spring_risk")
    >>> float(obs[k]) >= 0.5
    True
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import TransformObservation
from gymnasium.wrappers.vector import TransformObservation as VectorTransformObservation

from prognostics.metrics import RiskMap
from scas_env.actuator.params import ScasParams
from scas_env.core.scenario import Scenario
from scas_env.core.setup import PARTS
from scas_env.utils.atomic_file import write_text_atomic

__all__ = ["FREE_FIELDS", "check_fitted_on", "load_risk_maps", "recalibrate_risk", "save_risk_maps"]

#: Scenario fields a map does not depend on: what the observation shows and how long an
#: episode runs (the filters and the parts' lives are the same)
FREE_FIELDS: tuple[str, ...] = ("obs_mode", "episode_slots")
_FILE_KEYS = ("scenario", "params", "maps", "command")


def save_risk_maps(
    path: str | Path,
    maps: Mapping[str, RiskMap],
    scenario: Scenario,
    params: ScasParams,
    command: str = "",
    *,
    overwrite: bool = False,
) -> None:
    """Write ``maps`` (part -> map) with the scenario and parameters they were fitted on, and
    the ``command`` that fitted them, to the JSON file ``path`` (atomically; an existing file
    only with ``overwrite``)."""
    _check_maps(maps)
    if Path(path).exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    data = {
        "scenario": scenario.to_dict(),
        "params": params.to_dict(),
        "maps": {part: m.to_dict() for part, m in maps.items()},
        "command": str(command),
    }
    write_text_atomic(path, json.dumps(data, indent=1) + "\n")


def load_risk_maps(path: str | Path) -> tuple[dict[str, RiskMap], Scenario, ScasParams]:
    """The maps of a file written by :func:`save_risk_maps`, with the scenario and
    parameters they were fitted on (unknown keys refused)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not a JSON risk-map file: {exc}") from None
    if not isinstance(data, dict) or sorted(data) != sorted(_FILE_KEYS):
        keys = sorted(data) if isinstance(data, dict) else type(data).__name__
        raise ValueError(f"{path}: a risk-map file holds the keys {list(_FILE_KEYS)}, got {keys}")
    if not isinstance(data["maps"], dict):
        raise ValueError(f"{path}: 'maps' must map parts to maps, got {data['maps']!r}")
    maps = {part: RiskMap.from_dict(m) for part, m in data["maps"].items()}
    _check_maps(maps)
    return maps, Scenario.from_dict(data["scenario"]), ScasParams.from_dict(data["params"])


def _check_maps(maps: Mapping[str, RiskMap]) -> None:
    if not isinstance(maps, Mapping) or not maps:
        raise ValueError(f"maps = {maps!r} must be a non-empty mapping of part -> RiskMap")
    for part, m in maps.items():
        if part not in PARTS:
            raise ValueError(f"maps: part {part!r} must be one of {PARTS}")
        if not isinstance(m, RiskMap):
            raise TypeError(f"maps[{part!r}] = {m!r} must be a prognostics.metrics.RiskMap")


def check_fitted_on(env_scenario: Scenario, env_params: ScasParams,
                     scenario: Scenario, params: ScasParams) -> None:  # fmt: skip
    """Refuse maps fitted on ``scenario`` and ``params`` for an env of ``env_scenario`` and
    ``env_params`` where beliefs depend on the difference (module docstring)."""
    ours, theirs = env_scenario.to_dict(), scenario.to_dict()
    differ = sorted(k for k in ours if k not in FREE_FIELDS and ours[k] != theirs[k])
    if differ:
        shown = ", ".join(f"{k} = {ours[k]!r} (maps: {theirs[k]!r})" for k in differ)
        raise ValueError(f"the env's scenario differs from the maps' where beliefs depend on it: "
                         f"{shown}; fit maps for this scenario")  # fmt: skip
    if env_params != params:
        raise ValueError("the env's ScasParams differ from those the maps were fitted on; "
                         "fit maps for these parameters")  # fmt: skip


def recalibrate_risk(
    env: gym.Env | gym.vector.VectorEnv,
    maps: Mapping[str, RiskMap],
    *,
    fitted_on: tuple[Scenario, ScasParams] | None = None,
) -> gym.Env | gym.vector.VectorEnv:
    """``env`` (a single env or the native vector env of ``ScasMaintenance-v2``) with the
    risk of each part in ``maps`` passed through its map (module docstring); ``fitted_on``
    (the scenario and parameters :func:`load_risk_maps` returns) is checked against the
    env's."""
    _check_maps(maps)
    base = env.unwrapped
    names = getattr(base, "obs_names", None)
    if names is None or not hasattr(base, "setup"):
        raise TypeError(f"env = {env!r} must be a ScasMaintenance env or its native vector env")
    if fitted_on is not None:
        check_fitted_on(base.setup.scenario, base.setup.params, *fitted_on)
    func = _RiskTransform(tuple(names), maps, base.setup.scenario.obs_mode == "dict")
    if isinstance(env, gym.vector.VectorEnv):
        return VectorTransformObservation(env, func)
    return TransformObservation(env, func, env.observation_space)


class _RiskTransform:
    """The observation transform: each mapped part's risk column through its map (a class,
    not a closure, so that the wrapped env pickles)."""

    def __init__(self, names: tuple[str, ...], maps: Mapping[str, RiskMap], is_dict: bool):
        self.maps = dict(maps)
        self.is_dict = is_dict
        if is_dict:  # names "group.entry"; the risks sit in the "filter" group
            group = [n.split(".", 1)[1] for n in names if n.startswith("filter.")]
            self.cols = {part: group.index(f"{part}_risk") for part in maps}
        else:
            self.cols = {part: names.index(f"{part}_risk") for part in maps}

    def __call__(self, obs: Any) -> Any:
        if self.is_dict:
            out = dict(obs)
            out["filter"] = self._mapped(obs["filter"])
            return out
        return self._mapped(obs)

    def _mapped(self, values: np.ndarray) -> np.ndarray:
        out = values.copy()
        for part, k in self.cols.items():
            risk = out[..., k].astype(np.float64)
            out[..., k] = self.maps[part](risk).astype(out.dtype)
        return out
