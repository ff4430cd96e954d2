"""Agent files read without unpickling: an SB3 zip's network.

An SB3 zip (``model.save``) holds three kinds of members: ``data`` (JSON: hyper-parameters,
the spaces, the policy class; parts of it are cloudpickled Python objects, which
``BaseAlgorithm.load`` unpickles), ``policy.pth`` (the network's tensors, a ``torch.save``
file) and optimizer state. :func:`read_sb3_policy` rebuilds the network from the JSON parts
of ``data`` alone and the tensors of ``policy.pth`` read with ``torch.load(weights_only=
True)``, which builds tensors and plain containers only: nothing in the file can run code.
The policy class named in ``data`` is looked up by name in stable-baselines3, sb3-contrib or
this package (never unpickled); a zip that needs more (keywords of its network that are
Python objects, a class elsewhere) is reported as :class:`NeedsPickle`, which the caller
turns into an error unless the user trusts the file (``trust_pickle=True``).

The observation statistics beside a zip (``*_normalization.json``) are
:mod:`policies.agents.obs_normalization`'s; the agents' random streams are
:mod:`policies.agents.policy_random`'s.
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import io
import json
import re
import zipfile
from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from policies.agents.policy_random import global_rngs_kept

__all__ = [
    "LoadedModel",
    "NeedsPickle",
    "build_policy",
    "read_json_file",
    "read_sb3_policy",
    "read_weights",
    "read_zip",
    "require_contrib",
    "weights_sha256",
    "zip_data",
    "zip_policy_class",
    "zip_tensors",
]

#: packages whose policy classes a zip may name (looked up by name, never unpickled)
POLICY_PACKAGES = ("stable_baselines3.", "sb3_contrib.", "policies.agents.")


class NeedsPickle(ValueError):
    """The file can only be read by unpickling Python objects from it (which runs code)."""


def read_json_file(path: Path, what: str) -> Any:
    """The JSON document of ``path``; a file that is not UTF-8 JSON (truncated, binary, another
    format) raises ``ValueError`` naming the file and ``what`` it should be."""
    try:
        text = Path(path).read_bytes().decode("utf-8")
        return json.loads(text)
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not a {what} (not UTF-8 text: {exc.reason})") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not a {what} (not valid JSON: {exc})") from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the {what}: {exc.strerror or exc}") from None


# ---------------------------------------------------------------------------- SB3 zips
def zip_data(path: Path) -> dict[str, Any]:
    """The JSON ``data`` member of an SB3 zip, checking every member's CRC first (a
    truncated or corrupted file raises ``ValueError`` naming it). Parsing JSON runs no code;
    the cloudpickled entries in it stay base64 text."""
    return read_zip(path)[0]


def read_zip(path: Path) -> tuple[dict[str, Any], bytes]:
    """``(data, policy.pth bytes)`` of an SB3 zip."""
    try:
        with zipfile.ZipFile(path) as zf:
            bad = zf.testzip()
            if bad is not None:
                raise ValueError(f"{path}: member {bad!r} is corrupted (CRC mismatch)")
            names = zf.namelist()
            for needed in ("data", "policy.pth"):
                if needed not in names:
                    raise ValueError(
                        f"{path}: not a complete SB3 model zip (truncated or corrupted?): no "
                        f"{needed!r} member; found {names[:4]}{'...' if len(names) > 4 else ''}"
                    )
            raw_data, weights = zf.read("data"), zf.read("policy.pth")
    except zipfile.BadZipFile as exc:
        raise ValueError(
            f"{path}: not a readable zip file (truncated or corrupted): {exc}"
        ) from None
    except OSError as exc:
        raise ValueError(f"{path}: cannot read: {exc.strerror or exc}") from None
    try:
        data = json.loads(raw_data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: its 'data' member is not JSON ({exc})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: its 'data' member is not a JSON object")
    return data, weights


def read_weights(path: str | Path) -> dict[str, Any]:
    """The tensors of an SB3 zip's ``policy.pth`` (``torch.load(weights_only=True)``: tensors
    and plain containers only); ``ValueError`` naming the file if it is not such a file."""
    path = Path(path)
    return zip_tensors(path, read_zip(path)[1])


def zip_tensors(path: Path, blob: bytes) -> dict[str, Any]:
    """The tensors of a zip's ``policy.pth`` bytes, loaded with ``weights_only=True`` (no
    code runs); a malformed blob raises ``ValueError`` naming ``path``."""
    import torch

    try:
        state = torch.load(io.BytesIO(blob), map_location="cpu", weights_only=True)
    except Exception as exc:  # any malformed byte string: torch raises many kinds
        first = str(exc).splitlines()[0] if str(exc) else ""
        raise ValueError(
            f"{path}: policy.pth is not a readable tensor file (corrupted?): "
            f"{type(exc).__name__}: {first}"
        ) from None
    if (
        not isinstance(state, dict)
        or not state
        or not all(isinstance(v, torch.Tensor) for v in state.values())
    ):
        raise ValueError(f"{path}: policy.pth holds no tensors of a network")
    return state


def weights_sha256(path: str | Path) -> str:
    """SHA-256 of the ``policy.pth`` member of an SB3 zip (what an agent's metadata records
    as ``weights_sha256``: a copy with changed weights is refused)."""
    return hashlib.sha256(read_zip(Path(path))[1]).hexdigest()


def _space_shapes(path: Path, data: Mapping[str, Any]) -> tuple[tuple[int, ...], int | None]:
    """The observation shape and the number of discrete actions (None: not ``Discrete``)
    that the zip's ``data`` records, read from its JSON fields."""

    def shape(entry: Any, what: str) -> tuple[int, ...]:
        raw = entry.get("_shape") if isinstance(entry, dict) else None
        if isinstance(raw, str):
            try:
                raw = json.loads(raw)
            except json.JSONDecodeError:
                raw = None
        if not isinstance(raw, list) or not all(
            isinstance(v, int) and not isinstance(v, bool) for v in raw
        ):
            raise ValueError(f"{path}: the zip does not record the {what}'s shape")
        return tuple(raw)

    obs_shape = shape(data.get("observation_space"), "observation space")
    action = data.get("action_space")
    kind = str(action.get(":type:", "")) if isinstance(action, dict) else ""
    if not kind.endswith("Discrete'>"):
        return obs_shape, None
    try:
        n = int(str(action.get("n")))
    except ValueError:
        raise ValueError(f"{path}: the zip does not record its number of actions") from None
    return obs_shape, n


def check_spaces(
    path: Path, data: Mapping[str, Any], obs_size: int, n_actions: int, env: str
) -> None:
    """Refuse a zip whose recorded spaces are not a flat ``Box(obs_size,)`` observation and
    ``Discrete(n_actions)`` actions (an agent of another env), naming the file."""
    obs_shape, n = _space_shapes(path, data)
    if obs_shape != (obs_size,) or n != n_actions:
        got_actions = f"Discrete({n})" if n is not None else "a non-discrete action space"
        raise ValueError(
            f"{path}: the agent was made for observations of shape {obs_shape} and "
            f"{got_actions}; {env} has observations ({obs_size},) and Discrete({n_actions})"
        )


def require_contrib(purpose: str) -> ModuleType:
    """``sb3_contrib``, or an ``ImportError`` naming the package and ``purpose``."""
    try:
        return importlib.import_module("sb3_contrib")
    except ImportError as exc:
        raise ImportError(
            f"to {purpose} you need sb3-contrib (a dependency of this package), which is "
            "not installed: pip install 'sb3-contrib>=2.3'"
        ) from exc


def zip_policy_class(path: Path, data: Mapping[str, Any]) -> type:
    """The policy class the zip names, looked up by module and name in
    :data:`POLICY_PACKAGES` (never unpickled); :class:`NeedsPickle` otherwise."""
    from stable_baselines3.common.policies import BasePolicy

    entry = data.get("policy_class")
    module = str(entry.get("__module__", "")) if isinstance(entry, dict) else ""
    init = str(entry.get("__init__", "")) if isinstance(entry, dict) else ""
    match = re.match(r"<function (\w+)\.__init__ at ", init)
    if not module.startswith(POLICY_PACKAGES) or match is None:
        raise NeedsPickle(
            f"its policy class ({module or 'unnamed'}) is not one of {POLICY_PACKAGES}"
        )
    try:
        cls = getattr(importlib.import_module(module), match.group(1), None)
    except ImportError as exc:
        if module.startswith("sb3_contrib"):
            require_contrib(f"load {path}")
        raise ValueError(f"{path}: its policy class's module {module!r}: {exc}") from None
    if not (isinstance(cls, type) and issubclass(cls, BasePolicy)):
        raise NeedsPickle(f"its policy class {module}.{match.group(1)} is not an SB3 policy")
    return cls


class LoadedModel:
    """The part of an SB3 algorithm that acting needs, around a policy network read by
    :func:`read_sb3_policy`: ``policy``, the spaces, ``policy_kwargs`` and ``predict`` (the
    policy's, as ``BaseAlgorithm.predict`` calls it). No ``set_random_seed``: SB3's re-seeds
    the process-global generators; the agents keep their own
    (:class:`~policies.agents.policy_random.PolicyRandom`)."""

    def __init__(self, policy: Any, policy_kwargs: Mapping[str, Any], source: Path) -> None:
        self.policy = policy
        self.observation_space = policy.observation_space
        self.action_space = policy.action_space
        self.policy_kwargs = dict(policy_kwargs)
        self.source = source
        #: MaskablePPO's policy: ``predict`` takes ``action_masks``
        self.masked = "action_masks" in inspect.signature(policy.predict).parameters

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = False,
        **kwargs: Any,
    ) -> tuple[np.ndarray, Any]:
        return self.policy.predict(observation, state, episode_start, deterministic, **kwargs)

    def __repr__(self) -> str:
        return f"LoadedModel({type(self.policy).__name__} from {self.source})"


def read_sb3_policy(
    path: str | Path, obs_size: int, n_actions: int, *, env: str = "the env"
) -> tuple[LoadedModel, dict[str, Any]]:
    """The network of an SB3 zip, read without unpickling, and the zip's ``data``.

    Checks, each raising ``ValueError`` naming the file: the zip is complete and its CRCs
    hold; its recorded spaces are ``Box(obs_size,)`` and ``Discrete(n_actions)``
    (:func:`check_spaces`); ``policy.pth`` is a tensor file (``torch.load(weights_only=
    True)``) whose tensors fit the network the zip describes and are finite. Raises
    :class:`NeedsPickle` when the network can only be rebuilt from pickled objects.
    """
    import gymnasium as gym

    path = Path(path)
    data, blob = read_zip(path)
    check_spaces(path, data, obs_size, n_actions, env)
    obs_space = gym.spaces.Box(-np.inf, np.inf, shape=(obs_size,), dtype=np.float32)
    return build_policy(path, data, blob, obs_space, gym.spaces.Discrete(n_actions)), data


def build_policy(
    path: Path, data: Mapping[str, Any], blob: bytes, obs_space: Any, action_space: Any
) -> LoadedModel:
    """The network a zip's ``data`` names for these spaces, with the tensors of ``blob``
    (its ``policy.pth``), in evaluation mode; nothing is unpickled. Raises
    :class:`NeedsPickle` if the network needs pickled objects, ``ValueError`` naming
    ``path`` if its keywords do not build it or its tensors do not fit or are not finite."""
    cls = zip_policy_class(path, data)
    kwargs = data.get("policy_kwargs", {})
    if not isinstance(kwargs, dict) or ":serialized:" in kwargs:
        raise NeedsPickle("its network's keywords (policy_kwargs) are pickled Python objects")
    state = zip_tensors(path, blob)
    extra: dict[str, Any] = {}
    if "use_sde" in inspect.signature(cls.__init__).parameters:
        extra["use_sde"] = bool(data.get("use_sde", False))
    try:
        with global_rngs_kept():  # its initial weights, drawn here, are replaced below
            policy = cls(obs_space, action_space, lambda _: 0.0, **extra, **kwargs)
    except TypeError as exc:
        raise ValueError(
            f"{path}: its policy_kwargs {kwargs} do not build a {cls.__name__}: {exc}"
        ) from None
    try:
        policy.load_state_dict(state)
    except RuntimeError as exc:
        first = str(exc).splitlines()[0]
        raise ValueError(
            f"{path}: its weights do not fit the network it describes: {first}"
        ) from None
    if not all(bool(t.isfinite().all()) for t in state.values() if t.is_floating_point()):
        raise ValueError(f"{path}: the policy has non-finite parameters (corrupted)")
    policy.set_training_mode(False)
    return LoadedModel(policy, kwargs, path)
