"""The monitor's risk outputs through fitted recalibration maps: a wrapper and its file.

The observation's ``spring_risk`` and ``seal_risk`` are each filter's ``P(fail within
Scenario.risk_horizon_flights)``. :func:`recalibrate_risk` wraps a single env or the native
vector env (:class:`gymnasium.wrappers.TransformObservation` and its vector form) so that
they pass through :class:`prognostics.metrics.RiskMap` s fitted on training lives
(``python -m experiments.risk_recalibration``; docs/beliefs.md, "Recalibrated risk"): every
other entry, the action space, the rewards and ``info`` (whose beliefs stay the filters')
are unchanged, the mapped risk is cast to float32 as the observation is. Only the
observation modes of :data:`RISK_OBS_MODES` show the risks.

A map belongs to the monitor and the world it was fitted on. :func:`save_risk_maps` writes
the maps with a :class:`FittedOn` record: the scenario and parameters, the world's
:class:`~scas_env.core.mismatch.Mismatch`, and SHA-256 digests (:func:`table_digest`) of
the calibration, the monitor's feature surrogate and the world's own surrogate.
:func:`read_risk_maps` returns the maps and that record, and :func:`recalibrate_risk`
refuses an env that differs from it, naming the fields: in the scenario outside
:data:`FREE_FIELDS` (fields that change neither what the filters believe nor how the parts
live), the parameters, the mismatch, the calibration or either surrogate (``transfer=True``
accepts another mismatch, calibration or surrogate: a transfer study). A file without the
world's fields stands for the defaults of its parameters (no mismatch, the calibration and
surrogate an env built on them runs on, no world surrogate). :func:`load_risk_maps` returns
the maps, scenario and parameters of a file fitted on those defaults.

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
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import TransformObservation
from gymnasium.wrappers.vector import TransformObservation as VectorTransformObservation

from prognostics.metrics import RiskMap
from scas_env.actuator.calibration import Calibration
from scas_env.actuator.params import ScasParams
from scas_env.actuator.surrogate import SurrogateModel
from scas_env.core.mismatch import Mismatch
from scas_env.core.scenario import OBS_MODES, Scenario
from scas_env.core.setup import PARTS, Setup
from scas_env.utils.atomic_file import write_text_atomic
from scas_env.utils.shipped_files import json_sha256

__all__ = [
    "FREE_FIELDS",
    "RISK_OBS_MODES",
    "FittedOn",
    "check_fitted_on",
    "check_fitted_setup",
    "load_risk_maps",
    "read_risk_maps",
    "recalibrate_risk",
    "save_risk_maps",
    "table_digest",
]

#: Scenario fields a map does not depend on: what the observation shows and how long an
#: episode runs (the filters and the parts' lives are the same)
FREE_FIELDS: tuple[str, ...] = ("obs_mode", "episode_slots")
#: observation modes that show the filters' risks (``"dict"`` in its ``filter`` group)
RISK_OBS_MODES: tuple[str, ...] = ("features+rul", "dict")
_FILE_KEYS = ("scenario", "params", "maps", "command")
#: the digests of :class:`FittedOn`
_DIGESTS = ("calibration_sha256", "surrogate_sha256", "world_surrogate_sha256")
#: the world's fields of a file (:class:`FittedOn`); a file without them stands for defaults
_WORLD_KEYS = ("mismatch", *_DIGESTS)
_SHA256 = re.compile(r"^[0-9a-f]{64}$")


def table_digest(table: Calibration | SurrogateModel) -> str:
    """SHA-256 (hex) of a calibration's or feature surrogate's ``to_dict()`` as JSON with
    sorted keys: equal digests, equal tables."""
    return json_sha256(table.to_dict())


@dataclass(frozen=True)
class FittedOn:
    """What risk maps were fitted on (module docstring).

    ``calibration_sha256`` and ``surrogate_sha256`` of ``None`` stand for the tables an env
    built on ``params`` runs on without them (told without building one: the shipped
    tables, or a calibration of these params with the env's build settings);
    ``world_surrogate_sha256`` of ``None`` for no world surrogate of its own (the world's
    features from the monitor's).
    """

    scenario: Scenario
    params: ScasParams
    mismatch: Mismatch = field(default_factory=Mismatch)
    calibration_sha256: str | None = None
    surrogate_sha256: str | None = None
    world_surrogate_sha256: str | None = None

    def __post_init__(self) -> None:
        for name, cls in (("scenario", Scenario), ("params", ScasParams), ("mismatch", Mismatch)):
            if not isinstance(getattr(self, name), cls):
                raise ValueError(f"{name} = {getattr(self, name)!r} must be a {cls.__name__}")
        for name in _DIGESTS:
            value = getattr(self, name)
            if value is not None and not (isinstance(value, str) and _SHA256.match(value)):
                raise ValueError(f"{name} = {value!r} must be None or 64 lower-case hex digits")

    def world_fields(self) -> dict[str, Any]:
        """The file's fields of the world (``mismatch`` and the three digests)."""
        return {
            "mismatch": self.mismatch.to_dict(),
            **{name: getattr(self, name) for name in _DIGESTS},
        }


def save_risk_maps(
    path: str | Path,
    maps: Mapping[str, RiskMap],
    scenario: Scenario,
    params: ScasParams,
    command: str = "",
    *,
    overwrite: bool = False,
    mismatch: Mismatch | None = None,
    calibration: Calibration | None = None,
    surrogate: SurrogateModel | None = None,
    world_surrogate: SurrogateModel | None = None,
) -> None:
    """Write ``maps`` (part -> map) with what they were fitted on (:class:`FittedOn`: the
    scenario, parameters, mismatch, and digests of the calibration, surrogate and world
    surrogate; ``None``: the defaults of an env built on ``params``) and the ``command``
    that fitted them, to the JSON file ``path`` (atomically; an existing file only with
    ``overwrite``)."""
    _check_maps(maps)
    for name, value, cls in (
        ("calibration", calibration, Calibration),
        ("surrogate", surrogate, SurrogateModel),
        ("world_surrogate", world_surrogate, SurrogateModel),
    ):
        if value is not None and not isinstance(value, cls):
            raise ValueError(f"{name} = {value!r} must be None (the default) or a {cls.__name__}")
    fitted = FittedOn(
        scenario,
        params,
        Mismatch() if mismatch is None else mismatch,
        None if calibration is None else table_digest(calibration),
        None if surrogate is None else table_digest(surrogate),
        None if world_surrogate is None else table_digest(world_surrogate),
    )
    if Path(path).exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True to replace it")
    data = {
        "scenario": scenario.to_dict(),
        "params": params.to_dict(),
        **fitted.world_fields(),
        "maps": {part: m.to_dict() for part, m in maps.items()},
        "command": str(command),
    }
    write_text_atomic(path, json.dumps(data, indent=1) + "\n")


def read_risk_maps(path: str | Path) -> tuple[dict[str, RiskMap], FittedOn]:
    """The maps of a file written by :func:`save_risk_maps` and what they were fitted on
    (unknown keys refused; a file without the world's fields: their defaults)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path} is not a JSON risk-map file: {exc}") from None
    keys = sorted(data) if isinstance(data, dict) else type(data).__name__
    if not isinstance(data, dict) or not (
        set(_FILE_KEYS) <= set(data) <= set(_FILE_KEYS) | set(_WORLD_KEYS)
    ):
        raise ValueError(
            f"{path}: a risk-map file holds the keys {list(_FILE_KEYS)} and optionally "
            f"{list(_WORLD_KEYS)}, got {keys}"
        )
    if not isinstance(data["maps"], dict):
        raise ValueError(f"{path}: 'maps' must map parts to maps, got {data['maps']!r}")
    maps = {part: RiskMap.from_dict(m) for part, m in data["maps"].items()}
    _check_maps(maps)
    try:
        fitted = FittedOn(
            Scenario.from_dict(data["scenario"]),
            ScasParams.from_dict(data["params"]),
            Mismatch.from_dict(data.get("mismatch", {})),
            **{name: data.get(name) for name in _DIGESTS},
        )
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None
    return maps, fitted


def load_risk_maps(path: str | Path) -> tuple[dict[str, RiskMap], Scenario, ScasParams]:
    """The maps of a file written by :func:`save_risk_maps`, with the scenario and
    parameters they were fitted on, for ``recalibrate_risk(..., fitted_on=(scenario,
    params))``; a file fitted on anything but the defaults of those parameters (a
    mismatch, another calibration or surrogate, a world surrogate) is refused here, naming
    the fields: :func:`read_risk_maps` returns its full record."""
    maps, fitted = read_risk_maps(path)
    cal, sur = _default_digests(fitted.params)
    differ = [f"mismatch.{k} = {v!r}" for k, v in fitted.mismatch.changed().items()]
    for name, value, known in (
        ("calibration_sha256", fitted.calibration_sha256, cal),
        ("surrogate_sha256", fitted.surrogate_sha256, sur),
        ("world_surrogate_sha256", fitted.world_surrogate_sha256, None),
    ):
        if value is not None and value != known:
            differ.append(f"{name} = {value}")
    if differ:
        raise ValueError(
            f"{path}: the maps were fitted on more than a scenario and params "
            f"({'; '.join(differ)}); read it with read_risk_maps and pass its FittedOn "
            "record as recalibrate_risk(..., fitted_on=...)"
        )
    return maps, fitted.scenario, fitted.params


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
    ``env_params`` where beliefs depend on the difference (module docstring); the world's
    fields: :func:`check_fitted_setup`."""
    ours, theirs = env_scenario.to_dict(), scenario.to_dict()
    differ = sorted(k for k in ours if k not in FREE_FIELDS and ours[k] != theirs[k])
    if differ:
        shown = ", ".join(f"{k} = {ours[k]!r} (maps: {theirs[k]!r})" for k in differ)
        raise ValueError(f"the env's scenario differs from the maps' where beliefs depend on it: "
                         f"{shown}; fit maps for this scenario")  # fmt: skip
    if env_params != params:
        raise ValueError("the env's ScasParams differ from those the maps were fitted on; "
                         "fit maps for these parameters")  # fmt: skip


def _default_digests(params: ScasParams) -> tuple[str | None, str | None]:
    """The digests of the calibration and surrogate an env built on ``params`` runs on,
    where they are known without building anything: the shipped tables' for the shipped
    parameters (``None`` for one that would be built, or for no shipped surrogate)."""
    from scas_env.actuator.calibration import default_calibration, params_digest
    from scas_env.actuator.surrogate import shipped_surrogate_for

    shipped = default_calibration()
    cal = table_digest(shipped) if shipped.params_digest == params_digest(params) else None
    try:
        sur: str | None = table_digest(shipped_surrogate_for(params))
    except ValueError:
        sur = None
    return cal, sur


def _is_env_default(calibration: Calibration, params: ScasParams) -> bool:
    """Whether ``calibration`` is the one an env built on ``params`` runs on when none is
    passed (:func:`~scas_env.actuator.calibration.env_calibration`: the shipped one, or one
    built with :data:`~scas_env.actuator.calibration.ENV_BUILD`), told without building."""
    from scas_env.actuator.calibration import ENV_BUILD, params_digest

    cal, _ = _default_digests(params)
    if cal is not None:
        return table_digest(calibration) == cal
    return (
        calibration.params_digest == params_digest(params)
        and calibration.seed == ENV_BUILD["seed"]
        and calibration.whole_flights == ENV_BUILD["whole_flights"]
    )


def _world_differences(setup: Setup, fitted: FittedOn) -> list[str]:
    """``"field = the env's (maps: theirs)"`` for each world field where the env of ``setup``
    differs from ``fitted`` (a digest of ``None``: the env's default for the params)."""
    mine, maps = setup.mismatch.to_dict(), fitted.mismatch.to_dict()
    out = [f"mismatch.{k} = {mine[k]!r} (maps: {maps[k]!r})" for k in mine if mine[k] != maps[k]]
    default = "the default for their params"
    cal = table_digest(setup.calibration)
    if fitted.calibration_sha256 is None:
        if not _is_env_default(setup.calibration, setup.params):
            out.append(f"calibration_sha256 = {cal} (maps: {default})")
    elif cal != fitted.calibration_sha256:
        out.append(f"calibration_sha256 = {cal} (maps: {fitted.calibration_sha256})")
    sur = table_digest(setup.surrogate)
    expected = fitted.surrogate_sha256 or _default_digests(setup.params)[1]
    if sur != expected:
        out.append(f"surrogate_sha256 = {sur} (maps: {expected or default})")
    world = setup.world_surrogate
    world_sur = None if world is None else table_digest(world)
    if world_sur != fitted.world_surrogate_sha256:
        out.append(
            f"world_surrogate_sha256 = {world_sur or 'none'} "
            f"(maps: {fitted.world_surrogate_sha256 or 'none'})"
        )
    return out


def check_fitted_setup(setup: Setup, fitted: FittedOn, *, transfer: bool = False) -> None:
    """Refuse maps fitted on ``fitted`` for an env of ``setup`` (``env.unwrapped.setup``)
    whose scenario or parameters differ (:func:`check_fitted_on`) or, unless ``transfer``,
    whose mismatch, calibration, surrogate or world surrogate do; the ``ValueError`` names
    each differing field."""
    if not isinstance(fitted, FittedOn):
        raise ValueError(f"fitted = {fitted!r} must be a FittedOn record (read_risk_maps)")
    if not isinstance(transfer, bool):
        raise ValueError(f"transfer = {transfer!r} must be True or False")
    check_fitted_on(setup.scenario, setup.params, fitted.scenario, fitted.params)
    if transfer:
        return
    differ = _world_differences(setup, fitted)
    if differ:
        raise ValueError(
            f"the env's world or model differs from the one the maps were fitted on: "
            f"{'; '.join(differ)}; fit maps for this env, or pass transfer=True to apply "
            "them to it knowingly (a transfer study)"
        )


def recalibrate_risk(
    env: gym.Env | gym.vector.VectorEnv,
    maps: Mapping[str, RiskMap],
    *,
    fitted_on: FittedOn | tuple[Scenario, ScasParams] | None = None,
    transfer: bool = False,
) -> gym.Env | gym.vector.VectorEnv:
    """``env`` (a single env or the native vector env of ``ScasMaintenance-v2``, of an
    observation mode of :data:`RISK_OBS_MODES`) with the risk of each part in ``maps``
    passed through its map (module docstring). ``fitted_on`` (:func:`read_risk_maps`'s
    record, or the scenario and parameters :func:`load_risk_maps` returns, which stand for
    their defaults) is checked against the env's (:func:`check_fitted_setup`;
    ``transfer=True`` accepts another mismatch, calibration or surrogate)."""
    _check_maps(maps)
    base = env.unwrapped
    names = getattr(base, "obs_names", None)
    if names is None or not hasattr(base, "setup"):
        raise TypeError(f"env = {env!r} must be a ScasMaintenance env or its native vector env")
    mode = base.setup.scenario.obs_mode
    if mode not in RISK_OBS_MODES:
        raise ValueError(
            f"obs_mode = {mode!r} shows no risk to recalibrate; the modes that show the "
            f"filters' risks are {RISK_OBS_MODES} (of {OBS_MODES})"
        )
    if not isinstance(transfer, bool):
        raise ValueError(f"transfer = {transfer!r} must be True or False")
    if fitted_on is not None:
        if not isinstance(fitted_on, FittedOn):
            if not (isinstance(fitted_on, tuple) and len(fitted_on) == 2):
                raise ValueError(
                    f"fitted_on = {fitted_on!r} must be None, a FittedOn record "
                    "(read_risk_maps) or a (Scenario, ScasParams) pair (load_risk_maps)"
                )
            fitted_on = FittedOn(*fitted_on)
        check_fitted_setup(base.setup, fitted_on, transfer=transfer)
    func = _RiskTransform(tuple(names), maps, mode == "dict")
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
