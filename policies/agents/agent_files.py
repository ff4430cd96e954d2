"""Agent files read without unpickling: an SB3 zip's network and the observation statistics.

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

The observation statistics of ``VecNormalize`` (a pickle, ``*_vecnormalize.pkl``) are kept
in a JSON file of this project, ``*_normalization.json`` (:class:`ObsNormalization`): the
running mean and variance of the observations (float64, exact), ``epsilon`` and
``clip_obs``, and for resuming training the return statistics. Its ``normalize_obs`` is
``VecNormalize.normalize_obs`` (the same arithmetic, bit for bit; tested).

>>> norm = ObsNormalization(mean=[1.0, 2.0], var=[4.0, 1.0])
>>> norm.normalize_obs([3.0, 2.0]).tolist()
[1.0, 0.0]
"""

from __future__ import annotations

import hashlib
import importlib
import inspect
import io
import json
import math
import re
import zipfile
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

__all__ = [
    "NORMALIZATION_FORMAT",
    "LoadedModel",
    "NeedsPickle",
    "ObsNormalization",
    "PolicyRandom",
    "build_policy",
    "convert_vecnormalize",
    "global_rngs_kept",
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

#: the ``format`` entry of a normalisation file (with ``version``)
NORMALIZATION_FORMAT = "scas-maintenance-gym/obs-normalization"
NORMALIZATION_VERSION = 1
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


# ---------------------------------------------------------------------------- statistics
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
        this file has them)."""
        if venv.obs_rms.mean.shape != self.mean.shape:
            raise ValueError(
                f"the statistics are of {self.size} observation entries, the env's "
                f"{venv.obs_rms.mean.shape}"
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
    the process-global generators; the agents keep their own (:class:`PolicyRandom`)."""

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


@contextmanager
def global_rngs_kept() -> Iterator[None]:
    """Run a block of library code that draws from or re-seeds the process-global generators
    and put the states of ``random``, ``numpy.random`` and torch's CPU generator back after:
    building a network draws its initial weights (overwritten by the file's) from torch's,
    and SB3's ``BaseAlgorithm.load`` re-seeds all three with the seed saved in the zip."""
    import random

    import torch

    py_state = random.getstate()
    np_state = np.random.get_state()  # noqa: NPY002 (saved to be put back, never drawn from)
    try:
        with torch.random.fork_rng(devices=[]):
            yield
    finally:
        random.setstate(py_state)
        np.random.set_state(np_state)  # noqa: NPY002 (the caller's state, put back)


class PolicyRandom:
    """An agent's own random streams for ``deterministic=False`` actions: the project's one
    random path, so the process-global ``torch``, ``numpy`` and ``random`` generators are
    neither drawn from nor re-seeded (SB3's ``set_random_seed`` would re-seed all three).

    - ``torch``: the state of a CPU ``torch.Generator`` seeded with ``seed`` (the state
      ``torch.manual_seed(seed)`` would give). SB3's ``predict`` samples from the global CPU
      generator, so :meth:`torch_stream` runs a block with the global state swapped for this
      one (``torch.random.fork_rng``: the caller's state is put back after, this one saved).
      The agents act on the CPU (``device="cpu"``), so no CUDA state is involved.
    - ``numpy``: a ``numpy.random.Generator`` seeded with ``seed``, for draws the agent makes
      itself (a DQN's epsilon-greedy exploration, :class:`policies.agents.sb3_agents.SB3Agent`).

    ``seed=None`` (also a new object given no seed) seeds both from fresh operating-system
    entropy: not reproducible, and still no global generator touched.

    >>> import torch
    >>> rng, before = PolicyRandom(seed=3), torch.get_rng_state()
    >>> with rng.torch_stream():
    ...     a = torch.rand(2)
    >>> bool((torch.get_rng_state() == before).all())  # the global generator: untouched
    True
    >>> bool((a == torch.rand(2, generator=torch.Generator().manual_seed(3))).all())
    True
    """

    def __init__(self, seed: int | Sequence[int] | None = None) -> None:
        self.seed(seed)

    def seed(self, seed: int | Sequence[int] | None) -> None:
        """Re-seed both streams. A sequence of seeds (a batch of episodes) uses its first
        seed: one stream serves the whole batch (module docstring of the agents)."""
        import torch

        if seed is not None and np.ndim(seed) > 0:  # a batch's seeds (a list, an array)
            batch = np.ravel(np.asarray(seed))
            seed = int(batch[0]) if batch.size else None
        if seed is None:
            entropy = np.random.SeedSequence()
            self.numpy = np.random.default_rng(entropy)
            torch_seed = int(entropy.generate_state(1, np.uint64)[0])
        else:
            torch_seed = int(seed) % 2**32  # as SB3's set_random_seed did (numpy's range)
            self.numpy = np.random.default_rng(torch_seed)
        self._torch_state = torch.Generator().manual_seed(torch_seed).get_state()

    @contextmanager
    def torch_stream(self) -> Iterator[None]:
        """Within the block torch's global CPU generator draws from this stream; after it,
        the global generator is back where it was and this stream continues from where the
        block left it (also when the block raises)."""
        import torch

        with torch.random.fork_rng(devices=[]):
            torch.set_rng_state(self._torch_state)
            try:
                yield
            finally:
                self._torch_state = torch.get_rng_state()


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
