"""Trained agents as policies of this project: load any SB3 zip, or any ``module:factory``.

Every object returned here follows the policy protocol of :mod:`policies.base`:
``predict(observation, state=None, episode_start=None, deterministic=True)`` on **raw**
``ScasMaintenance-v2`` observations (one ``(n,)`` or a batch ``(n_envs, n)``).

- :func:`load_sb3_policy` turns an SB3 zip (saved by this project, by RL-Zoo or by plain
  ``model.save``) into an :class:`SB3Agent` (per-flight agent) or an :class:`EpochAgent`
  (an agent trained on :class:`scas_env.decision_epochs.DecisionEpochs`, replayed flight by
  flight: it decides, commits to ``k`` slots, then decides again). Its observation
  statistics are found beside the zip (:func:`find_statistics`) and are **required** when
  the agent was trained with them (its ``<name>.json`` or RL-Zoo ``config.yml`` says so).
- :func:`load_factory` builds any object with SB3's ``predict`` from ``"module:factory"``.

Both are registered (``"sb3"`` and ``"factory"``) so the benchmark can rebuild them by name in
its workers: ``PolicySpec("sb3", params={"path": PATH}, module="policies.agents.sb3_agents")``
and ``PolicySpec("factory", params={"target": "pkg.mod:make"},
module="policies.agents.sb3_agents")``.

Safety. Loading an agent unpickles nothing by default: the network is rebuilt from the JSON
of the zip and its ``policy.pth`` tensors (``torch.load(weights_only=True)``), the
observation statistics come from a JSON file (``<name>_normalization.json``,
:mod:`policies.agents.obs_normalization`), and the model's observation and action spaces are
checked against the env before it acts. A file that only SB3's own loader can read (a zip
whose network keywords are pickled objects, a ``*_vecnormalize.pkl``) is refused unless
``trust_pickle=True``: unpickling runs code chosen by whoever made the file. The shipped
agent in ``policies/data`` is also checked against the SHA-256 manifest of shipped files
(``scas_env/actuator/data/shipped_files.json``), and an agent whose metadata records
``weights_sha256`` against it (a corrupted or altered copy is refused). ``module:factory``
imports and runs that module's code: trusted code only.

Randomness. With ``deterministic=True`` (the benchmark's) an agent draws nothing. With
``deterministic=False`` it samples from its own streams
(:class:`policies.agents.policy_random.PolicyRandom`), never from the process-global ``torch``,
``numpy`` or ``random`` generators, and ``reset(seed)`` re-seeds only those streams (SB3's
``set_random_seed``, which re-seeds all three, is not called).
A batch of seeds (``reset(seed=[s0, s1, ...])``, one per row, as the benchmark passes them)
seeds **one** stream from its first seed ``s0``: the network samples the whole batch at once,
so a row's stochastic actions depend on ``s0``, on the row's place in the batch and on the
other rows' observations; the same batch with the same seeds gives the same actions.
"""

from __future__ import annotations

import importlib
import pickle
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from policies.agents.agent_files import (
    NeedsPickle,
    read_json_file,
    read_sb3_policy,
    require_contrib,
    weights_sha256,
    zip_data,
)
from policies.agents.obs_normalization import ObsNormalization
from policies.agents.policy_random import PolicyRandom, global_rngs_kept
from policies.base import check_finite, register_policy
from scas_env.decision_epochs import (
    DELEGATE,
    FLY,
    MASK_READS,
    N_MAINTENANCE,
    check_ks,
    delegate_actions,
    maintenance_mask,
    with_delegation,
)
from scas_env.utils.shipped_files import verify_shipped_file

DATA_DIR = Path(__file__).resolve().parents[1] / "data"
#: The shipped agent (model zip; its statistics and metadata sit beside it): MaskablePPO on
#: decision epochs of ``ScasMaintenance-v2``, warm-started from the tuned filter rule (the
#: benchmark's ``ppo``; ``policies/data/README.md``).
DEFAULT_AGENT = DATA_DIR / "maskable_ppo_epochs_v2.zip"

__all__ = [
    "DEFAULT_AGENT",
    "EpochAgent",
    "SB3Agent",
    "algo_class",
    "check_manifest",
    "find_statistics",
    "load_factory",
    "load_sb3_policy",
    "require_contrib",
]


# ---------------------------------------------------------------------------- file checks
def check_manifest(path: Path) -> None:
    """Refuse a shipped file (``policies/data``) whose SHA-256 differs from the package's
    manifest of shipped files (:func:`scas_env.utils.shipped_files.verify_shipped_file`);
    files elsewhere are not checked: they are the user's."""
    verify_shipped_file(path)


# ---------------------------------------------------------------------------- algorithms
#: policy-class module prefix -> algorithm (``package:Class``)
_POLICY_MODULES = (
    ("sb3_contrib.common.maskable", "sb3_contrib:MaskablePPO"),
    ("sb3_contrib.common.recurrent", "sb3_contrib:RecurrentPPO"),
    ("sb3_contrib.qrdqn", "sb3_contrib:QRDQN"),
    ("stable_baselines3.dqn", "stable_baselines3:DQN"),
    ("stable_baselines3.common.policies", "stable_baselines3:PPO"),
)
ALGO_NAMES = {
    "ppo": "stable_baselines3:PPO",
    "a2c": "stable_baselines3:A2C",
    "dqn": "stable_baselines3:DQN",
    "maskable_ppo": "sb3_contrib:MaskablePPO",
    "recurrent_ppo": "sb3_contrib:RecurrentPPO",
    "qrdqn": "sb3_contrib:QRDQN",
}


def _import(target: str) -> Any:
    module, _, name = target.partition(":")
    if module == "sb3_contrib":
        return getattr(require_contrib(f"load a {name} agent"), name)
    return getattr(importlib.import_module(module), name)


def algo_class(algo: str | None, data: dict[str, Any]) -> Any:
    """The SB3 class to load a zip with: ``algo`` (:data:`ALGO_NAMES`) if given, else guessed
    from the module of the zip's policy class (A2C zips load as PPO: same policy)."""
    if algo is not None:
        if algo not in ALGO_NAMES:
            raise ValueError(f"algo = {algo!r} must be one of {sorted(ALGO_NAMES)}")
        return _import(ALGO_NAMES[algo])
    module = str(data.get("policy_class", {}).get("__module__", ""))
    for prefix, target in _POLICY_MODULES:
        if module.startswith(prefix):
            return _import(target)
    raise ValueError(
        f"cannot tell the algorithm of a zip whose policy class is in {module!r}; "
        f"pass algo= one of {sorted(ALGO_NAMES)}"
    )


def _masked(model: Any) -> bool:
    """A MaskablePPO model (SB3's, or its network read by :func:`read_sb3_policy`)."""
    return type(model).__name__ == "MaskablePPO" or bool(getattr(model, "masked", False))


# ---------------------------------------------------------------------------- agents
class SB3Agent:
    """A per-flight SB3 model acting on raw observations (policy protocol):
    ``predict`` normalises with the ``VecNormalize`` statistics (if any; not updated) and,
    for MaskablePPO, passes the action mask of the raw observation. An observation of
    another width or with non-finite entries (NaN, inf) raises ``ValueError`` naming them.

    Parameters
    ----------
    model : the SB3 model.
    normalizer : observation statistics with ``normalize_obs`` (an
        :class:`~policies.agents.obs_normalization.ObsNormalization` or a ``VecNormalize``), or
        ``None``.
    obs_names : names of the observation entries (the env's ``obs_names``).
    masked : pass action masks to ``model.predict``.
    """

    def __init__(
        self, model: Any, normalizer: Any, obs_names: Sequence[str], *, masked: bool = False
    ) -> None:
        self.model = model
        self.normalizer = normalizer
        self.obs_names = tuple(obs_names)
        self.masked = masked
        self.rng = PolicyRandom()
        if masked:
            missing = [n for n in MASK_READS if n not in self.obs_names]
            if missing:
                raise ValueError(f"obs_names lack {missing} that the action mask reads")
            self._mask_cols = [self.obs_names.index(n) for n in MASK_READS]

    def _check(self, observation: Any) -> np.ndarray:
        obs = np.asarray(observation, dtype=np.float32)
        n = len(self.obs_names)
        if obs.ndim not in (1, 2) or obs.shape[-1] != n:
            raise ValueError(f"observation has shape {obs.shape}; expected ({n},) or (n_envs, {n})")
        check_finite(obs, self.obs_names)  # the env saturates at finite bounds: a NaN is a bug
        return obs

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[int | np.ndarray, Any]:
        """Action for one raw observation (``int``) or a batch (``int64`` array)."""
        obs = self._check(observation)
        norm = self.normalizer.normalize_obs(obs) if self.normalizer is not None else obs
        kwargs: dict[str, Any] = {}
        if self.masked:
            kwargs["action_masks"] = maintenance_mask(*(obs[..., c] for c in self._mask_cols))
        actions, state = self._model_predict(
            norm, state=state, episode_start=episode_start, deterministic=deterministic, **kwargs
        )
        actions = np.asarray(actions, dtype=np.int64)
        return (int(actions) if obs.ndim == 1 else actions.reshape(-1)), state

    def _model_predict(
        self, obs: np.ndarray, *, deterministic: bool, **kwargs: Any
    ) -> tuple[np.ndarray, Any]:
        """``model.predict`` drawing from the agent's own streams (module docstring).

        ``deterministic=True``: called as it is (nothing is drawn). Otherwise SB3 samples
        from torch's global CPU generator, so the call runs on the agent's torch stream
        (:meth:`PolicyRandom.torch_stream`). A DQN or QR-DQN loaded by SB3's own loader
        (``trust_pickle``) explores epsilon-greedily with ``numpy.random`` and its action
        space's generator in ``predict``; that is done here instead, from the agent's numpy
        stream: each row independently (SB3 draws one coin for the whole batch; the same for
        one row) takes a uniform action with probability ``model.exploration_rate``, else the
        greedy one. (A DQN read without unpickling is a bare Q-network: always greedy.)
        """
        if deterministic:
            return self.model.predict(obs, deterministic=True, **kwargs)
        epsilon = getattr(self.model, "exploration_rate", None)
        if epsilon is None:
            with self.rng.torch_stream():
                return self.model.predict(obs, deterministic=False, **kwargs)
        actions, state = self.model.predict(obs, deterministic=True, **kwargs)
        actions = np.array(actions, dtype=np.int64)
        explore = self.rng.numpy.random(actions.shape) < float(epsilon)
        space = self.model.action_space
        start = int(getattr(space, "start", 0))
        uniform = self.rng.numpy.integers(start, start + int(space.n), size=actions.shape)
        return np.where(explore, uniform, actions), state

    def reset(self, seed: int | Sequence[int] | None = None) -> None:
        """New episode(s). ``seed`` re-seeds the agent's own random streams (for reproducible
        ``deterministic=False`` actions; the global generators are left alone): an ``int``,
        or a batch's seeds, one per row, of which the first seeds the one stream the batch
        shares (module docstring). ``None`` keeps the streams running."""
        if seed is not None:
            self.rng.seed(seed)


class EpochAgent(SB3Agent):
    """A decision-epoch agent replayed flight by flight on the per-flight env (policy protocol).

    At a decision slot it builds the decision-epoch observation (the per-flight observation plus
    ``flights_left = episode_slots - slots since episode_start``), asks the model for
    ``(maintenance action, k)`` (masked as :class:`~scas_env.decision_epochs.DecisionEpochs`
    does), plays the maintenance action now and ``fly`` for the next ``k - 1`` slots, then
    decides again. The per-env counters travel in the returned ``state`` (pass it back, as
    the benchmark does; ``episode_start`` resets them), so the same object serves batches.
    A per-flight episode played this way equals the decision-epoch episode on the same seed
    (tested). An episode longer than ``episode_slots`` is refused (``ValueError`` at its slot
    ``episode_slots``, where ``flights_left`` would reach 0: past the agent's horizon).
    With ``delegate`` (a stateless policy on the per-flight observation: a residual agent, see
    :mod:`policies.agents.delegation`) the model has a fifth maintenance choice, "the
    delegate for ``k`` slots": the delegate then acts at each of those slots.
    """

    def __init__(
        self,
        model: Any,
        normalizer: Any,
        obs_names: Sequence[str],
        *,
        ks: Sequence[int],
        episode_slots: int,
        masked: bool = True,
        delegate: Any = None,
    ) -> None:
        ks = check_ks(ks)
        episode_slots = _check_episode_slots(episode_slots)
        super().__init__(model, normalizer, obs_names, masked=False)
        self.ks = ks
        self.episode_slots = episode_slots
        self.masked_epochs = masked
        self.delegate = delegate
        choices = N_MAINTENANCE + (delegate is not None)
        n_actions = getattr(model.action_space, "n", None)
        if n_actions != choices * len(self.ks):
            raise ValueError(
                f"the model has {n_actions} actions; ks = {self.ks} "
                f"{'with' if delegate is not None else 'without'} a delegate needs "
                f"{choices * len(self.ks)}"
            )
        missing = [n for n in MASK_READS if n not in self.obs_names]
        if missing:
            raise ValueError(f"obs_names lack {missing} that the action mask reads")
        self._cols = [self.obs_names.index(n) for n in MASK_READS]

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[int | np.ndarray, Any]:
        """Per-flight action(s); ``state`` = ``(slot, remaining, delegating)`` arrays per env."""
        obs = self._check(observation)
        batch = np.atleast_2d(obs)
        n = len(batch)
        if state is None:
            slot, remaining = np.zeros(n, np.int64), np.zeros(n, np.int64)
            delegating = np.zeros(n, dtype=bool)
        else:
            slot, remaining = (np.array(s, dtype=np.int64) for s in state[:2])
            delegating = np.array(state[2], dtype=bool) if len(state) > 2 else np.zeros(n, bool)
        if episode_start is not None:
            start = np.broadcast_to(np.asarray(episode_start, dtype=bool), (n,))
            slot[start], remaining[start], delegating[start] = 0, 0, False
        if np.any(slot >= self.episode_slots):
            late = int(slot.max())
            raise ValueError(
                f"slot {late} of an episode: the episode is longer than the agent's horizon "
                f"episode_slots = {self.episode_slots} (flights_left would be "
                f"{self.episode_slots - late}); load the agent with episode_slots = the "
                "episode's length"
            )
        actions = np.zeros(n, np.int64)  # fly while committed
        due = np.flatnonzero(remaining <= 0)
        if due.size:
            left = (self.episode_slots - slot[due]).astype(np.float32)
            epoch_obs = np.column_stack([batch[due], left])
            norm = self.normalizer.normalize_obs(epoch_obs) if self.normalizer else epoch_obs
            if self.masked_epochs:
                m = maintenance_mask(*(batch[due][:, c] for c in self._cols))
                if self.delegate is not None:
                    m = with_delegation(m)
                chosen = self._masked_choice(
                    norm, np.repeat(m, len(self.ks), axis=-1), deterministic
                )
            else:
                chosen, _ = self._model_predict(norm, deterministic=deterministic)
            chosen = np.asarray(chosen, dtype=np.int64).reshape(-1)
            maintenance = chosen // len(self.ks)
            delegating[due] = maintenance == DELEGATE
            actions[due] = np.where(delegating[due], FLY, maintenance)
            remaining[due] = np.asarray(self.ks)[chosen % len(self.ks)]
        if delegating.any():
            actions[delegating] = delegate_actions(self.delegate, batch[delegating])
        remaining -= 1
        slot += 1
        out = int(actions[0]) if obs.ndim == 1 else actions
        return out, (slot, remaining, delegating)

    def _masked_choice(self, norm: np.ndarray, masks: np.ndarray, deterministic: bool) -> Any:
        """MaskablePPO's own ``predict`` with masks; for a plain PPO model carrying the same
        weights (the shipped copy, loadable without sb3-contrib) the same rule by hand: the
        masked actions' logits set to -inf, then argmax (or a sample)."""
        if _masked(self.model):
            return self._model_predict(norm, deterministic=deterministic, action_masks=masks)[0]
        import torch

        with torch.no_grad():
            obs_t, _ = self.model.policy.obs_to_tensor(norm)
            logits = self.model.policy.get_distribution(obs_t).distribution.logits
            logits = logits.masked_fill(~torch.as_tensor(masks), -torch.inf)
            if deterministic:
                return logits.argmax(dim=1).numpy()
            with self.rng.torch_stream():
                return torch.distributions.Categorical(logits=logits).sample().numpy()


def _check_episode_slots(episode_slots: Any) -> int:
    """``episode_slots`` as an ``int`` >= 1 (``ValueError`` naming it otherwise)."""
    if (
        isinstance(episode_slots, bool | np.bool_)
        or not isinstance(episode_slots, int | np.integer)
        or episode_slots < 1
    ):
        raise ValueError(
            f"episode_slots = {episode_slots!r} must be an integer >= 1 (the episode's length)"
        )
    return int(episode_slots)


# ---------------------------------------------------------------------------- loading
#: where the observation statistics of ``<stem>.zip`` are looked for, in this order: this
#: project's JSON (no unpickling), then VecNormalize pickles (need ``trust_pickle``)
STATISTICS_NAMES = (
    "{stem}_normalization.json",
    "normalization.json",
    "{stem}/normalization.json",
    "{stem}_vecnormalize.pkl",
    "vecnormalize.pkl",
    "{stem}/vecnormalize.pkl",
)
_TRUST = (
    "reading it would unpickle Python objects from the file, which runs code; pass "
    "trust_pickle=True (scas-benchmark --trust-pickle) if you trust the file"
)


#: a checkpoint of SB3's ``CheckpointCallback`` (``scas-train``'s ``ckpt_<n>_steps.zip``)
_CHECKPOINT = re.compile(r"^(?P<prefix>.+)_(?P<n>\d+)_steps$")


def find_statistics(path: Path) -> Path | None:
    """The observation statistics of the zip ``path``: for a checkpoint
    ``<prefix>_<n>_steps.zip`` its ``<prefix>_normalization_<n>_steps.json`` (``scas-train``)
    or SB3's ``<prefix>_vecnormalize_<n>_steps.pkl``, else the first of
    :data:`STATISTICS_NAMES` beside it (``<stem>_normalization.json`` is this project's;
    ``vecnormalize.pkl`` in ``<stem>/`` is RL-Zoo's layout, ``<log>/<env>.zip`` with
    ``<log>/<env>/``)."""
    stem = path.name.removesuffix(".zip")
    names = [name.format(stem=stem) for name in STATISTICS_NAMES]
    ckpt = _CHECKPOINT.match(stem)
    if ckpt:
        p, n = ckpt["prefix"], ckpt["n"]
        names[:0] = [f"{p}_normalization_{n}_steps.json", f"{p}_vecnormalize_{n}_steps.pkl"]
    for name in names:
        cand = path.parent / name
        if cand.is_file():
            return cand
    return None


def _trained_with_normalize(path: Path, meta: dict[str, Any]) -> bool | None:
    """True/False if the agent's metadata (``<stem>.json``) or RL-Zoo ``config.yml`` tells
    whether VecNormalize was used in training; None if nothing tells."""
    if "normalize" in meta:
        return bool(meta["normalize"])
    if meta:  # this project's metadata before the key existed: always normalised
        return True
    config = path.parent / path.name.removesuffix(".zip") / "config.yml"
    if config.is_file():
        raw = _read_zoo_config(config)
        pairs = raw if isinstance(raw, list) else list((raw or {}).items())
        for item in pairs:
            if isinstance(item, list | tuple) and len(item) == 2 and item[0] == "normalize":
                value = item[1]
                return bool(value) and str(value).lower() not in ("false", "none", "0")
    return None


def _read_zoo_config(path: Path) -> Any:
    """RL-Zoo's ``config.yml`` (``yaml.dump`` of an OrderedDict, tagged
    ``!!python/object/apply:collections.OrderedDict``) read safely: the tag becomes its list of
    ``[key, value]`` pairs, and no other Python tag is constructed."""
    import yaml

    class ZooLoader(yaml.SafeLoader):
        pass

    def ordered(loader: yaml.SafeLoader, node: yaml.Node) -> Any:
        items = loader.construct_sequence(node, deep=True)
        return items[0] if len(items) == 1 and isinstance(items[0], list) else items

    ZooLoader.add_constructor(
        "tag:yaml.org,2002:python/object/apply:collections.OrderedDict", ordered
    )
    try:
        return yaml.load(path.read_text(), Loader=ZooLoader)
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a readable RL-Zoo config.yml: {exc}") from exc


def _load_normalizer(path: Path, obs_dim: int, trust_pickle: bool) -> ObsNormalization:
    """The observation statistics in ``path``: a normalisation JSON, or (``trust_pickle``)
    a VecNormalize pickle; their size must be the model's observation size."""
    check_manifest(path)
    if path.suffix.lower() == ".json":
        normalizer = ObsNormalization.load(path)
    else:
        if not trust_pickle:
            raise ValueError(f"{path} is a VecNormalize pickle: {_TRUST}")
        from stable_baselines3.common.vec_env import VecNormalize

        try:
            with path.open("rb") as fh:
                venv = pickle.load(fh)  # trusted by the caller (trust_pickle=True)
        except Exception as exc:
            raise ValueError(f"{path}: cannot read VecNormalize statistics: {exc!r}") from exc
        if not isinstance(venv, VecNormalize):
            raise ValueError(f"{path}: holds a {type(venv).__name__}, not VecNormalize")
        try:
            normalizer = ObsNormalization.from_vecnormalize(venv)
        except ValueError as exc:
            raise ValueError(f"{path}: {exc}") from None
    if normalizer.size != obs_dim:
        raise ValueError(
            f"{path}: observation statistics of {normalizer.size} entries do not fit the "
            f"model's observation of size {obs_dim}"
        )
    return normalizer


def _run_metadata(path: Path) -> dict[str, Any]:
    """For a checkpoint ``<prefix>_<n>_steps.zip`` of a ``scas-train`` run, what the run's
    ``run.json`` beside it says of the agent (decision epochs ``ks``, ``episode_slots``,
    ``delegate``, ``algo``, ``normalize``); ``{}`` otherwise."""
    run_path = path.parent / "run.json"
    if not (_CHECKPOINT.match(path.name.removesuffix(".zip")) and run_path.is_file()):
        return {}
    run = read_json_file(run_path, "training run file")
    if not isinstance(run, dict) or not isinstance(run.get("ks"), list):
        return {}
    from scas_env.core.scenario import Scenario

    scenario = run.get("scenario") or {}
    meta = {
        "formulation": "decision_epochs",
        "ks": run["ks"],
        "episode_slots": scenario.get("episode_slots", Scenario().episode_slots),
        "normalize": run.get("normalize", True),  # scas-train's default
    }
    for key in ("algo", "delegate"):
        if run.get(key) is not None:
            meta[key] = run[key]
    return meta


def _metadata(path: Path) -> dict[str, Any]:
    """The agent's metadata ``<stem>.json`` beside the zip, else a ``scas-train``
    checkpoint's run (:func:`_run_metadata`); ``{}`` if there is neither."""
    meta_path = path.with_name(f"{path.name.removesuffix('.zip')}.json")
    if not meta_path.is_file():
        return _run_metadata(path)
    check_manifest(meta_path)
    meta = read_json_file(meta_path, "agent metadata file")
    if not isinstance(meta, dict):
        raise ValueError(f"{meta_path}: not an agent metadata file (expected a JSON object)")
    return meta


def _check_model(path: Path, model: Any, obs_size: int, n_actions: int, env: str) -> None:
    """A model loaded by SB3 (trusted path): the same space and finiteness checks as
    :func:`policies.agents.agent_files.read_sb3_policy`."""
    shape = tuple(model.observation_space.shape or ())
    n = getattr(model.action_space, "n", None)
    if shape != (obs_size,) or n != n_actions:
        raise ValueError(
            f"{path}: the agent was made for observations of shape {shape} and "
            f"{model.action_space}; {env} has observations ({obs_size},) and "
            f"Discrete({n_actions})"
        )
    for p in model.policy.parameters():
        if not bool(p.isfinite().all()):
            raise ValueError(f"{path}: the policy has non-finite parameters (corrupted)")


def load_sb3_policy(
    path: str | Path = DEFAULT_AGENT,
    obs_names: Sequence[str] | None = None,
    *,
    vecnormalize: str | Path | None = None,
    algo: str | None = None,
    ks: Sequence[int] | None = None,
    episode_slots: int | None = None,
    require_vecnormalize: bool | None = None,
    delegate: Any = None,
    trust_pickle: bool = False,
) -> SB3Agent:
    """An SB3 zip as a policy on raw observations of ``ScasMaintenance-v2``.

    By default nothing is unpickled (module docstring): the network is rebuilt from the
    zip's JSON and its ``policy.pth`` tensors, the observation statistics read from a
    normalisation JSON. The model's spaces are checked against the env's before use: a
    zip made for another observation or action space is refused, naming the file.

    Parameters
    ----------
    path : the model zip (this project's, RL-Zoo's, or any ``model.save``).
    obs_names : the env's observation names; checked against the agent's metadata when known.
    vecnormalize : its observation statistics: a normalisation ``.json``
        (:class:`policies.agents.obs_normalization.ObsNormalization`) or a VecNormalize ``.pkl``
        (needs ``trust_pickle``); default :func:`find_statistics`.
    algo : SB3 algorithm name (:data:`ALGO_NAMES`) for SB3's own loader (``trust_pickle``);
        default from metadata or the zip.
    ks, episode_slots : make it an :class:`EpochAgent` (decision epochs: slots per decision,
        episode length); default from the metadata ``<stem>.json`` (``"formulation":
        "decision_epochs"``); a ``ks`` other than the metadata's is refused.
    require_vecnormalize : True: missing statistics are an error; False: act without them;
        None (default): required if the metadata or RL-Zoo's ``config.yml`` says the agent was
        trained with VecNormalize.
    delegate : a residual decision-epoch agent's rule (a
        :class:`policies.agents.delegation.DelegateSpec` or its JSON mapping); default from
        the metadata (``"delegate"``).
    trust_pickle : allow reading a file that only SB3's unpickling loader reads (a zip whose
        network keywords are pickled objects, a VecNormalize ``.pkl``): **that runs code
        from the file**; only for files you trust.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"path = {str(path)!r} does not exist (expected an SB3 model .zip)")
    if not isinstance(trust_pickle, bool):
        raise ValueError(f"trust_pickle = {trust_pickle!r} must be True or False")
    if algo is not None and algo not in ALGO_NAMES:
        raise ValueError(f"algo = {algo!r} must be one of {sorted(ALGO_NAMES)}")
    if ks is not None:
        ks = check_ks(ks)
    if episode_slots is not None:
        episode_slots = _check_episode_slots(episode_slots)
    check_manifest(path)
    meta = _metadata(path)
    if ks is not None and meta.get("ks") is not None and ks != check_ks(meta["ks"]):
        raise ValueError(
            f"ks = {ks} differ from the agent's ks = {tuple(meta['ks'])} in its metadata "
            f"({path}: its actions mean those slots per decision); leave ks unset"
        )
    if (
        obs_names is not None
        and "obs_names" in meta
        and tuple(obs_names) != tuple(meta["obs_names"])
    ):
        raise ValueError(
            f"obs_names = {tuple(obs_names)} differ from the agent's {tuple(meta['obs_names'])}"
            f" ({path} was trained on another observation)"
        )
    names = tuple(obs_names if obs_names is not None else meta.get("obs_names", ()))
    if not names:
        raise ValueError(f"{path}: pass obs_names (the env's observation names)")
    ks = ks if ks is not None else meta.get("ks")
    spec = None
    if ks is not None:
        from policies.agents.delegation import DelegateSpec

        spec = delegate if delegate is not None else meta.get("delegate")
        if spec is not None and not isinstance(spec, DelegateSpec):
            spec = DelegateSpec.from_json(spec)
        ks = tuple(ks)
        obs_size = len(names) + 1
        n_actions = (N_MAINTENANCE + (spec is not None)) * len(ks)
        env = f"decision epochs (ks {ks}{', with a delegate' if spec else ''}) over this env"
    else:
        obs_size, n_actions, env = len(names), N_MAINTENANCE, "this env"
    recorded = meta.get("weights_sha256")
    if recorded is not None and weights_sha256(path) != recorded:
        raise ValueError(
            f"{path}: its policy.pth differs from the one its metadata records "
            "(weights_sha256): a corrupted or altered copy"
        )
    try:
        model, _ = read_sb3_policy(path, obs_size, n_actions, env=env)
    except NeedsPickle as why:
        if not trust_pickle:
            raise ValueError(f"{path}: {why}; {_TRUST}") from None
        cls = algo_class(algo if algo is not None else meta.get("algo"), zip_data(path))
        try:
            with global_rngs_kept():  # SB3's load re-seeds them with the zip's training seed
                model = cls.load(path, device="cpu")  # unpickles: trusted by the caller
        except Exception as exc:
            raise ValueError(f"{path}: SB3 cannot load this {cls.__name__} zip: {exc!r}") from exc
        _check_model(path, model, obs_size, n_actions, env)
    norm_path = Path(vecnormalize) if vecnormalize is not None else find_statistics(path)
    needed = require_vecnormalize
    if needed is None:
        needed = _trained_with_normalize(path, meta)
    normalizer = None
    if norm_path is not None and norm_path.is_file():
        normalizer = _load_normalizer(norm_path, obs_size, trust_pickle)
    elif vecnormalize is not None or needed:
        where = str(vecnormalize) if vecnormalize is not None else f"beside {path}"
        raise ValueError(
            f"{path} was trained with VecNormalize but its statistics are missing ({where}: "
            f"expected {path.name.removesuffix('.zip')}_normalization.json); without them it "
            "would act on unscaled observations. Pass vecnormalize=PATH, or "
            "require_vecnormalize=False if the agent was trained without it"
        )
    if ks is not None:
        slots = episode_slots if episode_slots is not None else meta.get("episode_slots")
        if slots is None:
            raise ValueError(f"{path}: a decision-epoch agent needs episode_slots")
        return EpochAgent(
            model,
            normalizer,
            names,
            ks=ks,
            episode_slots=slots,
            masked=_masked(model) or bool(meta.get("action_masks", False)),
            delegate=None if spec is None else spec.build(names),
        )
    return SB3Agent(model, normalizer, names, masked=_masked(model))


def load_factory(obs_names: Sequence[str], target: str, **params: Any) -> Any:
    """``factory(obs_names, **params)`` of ``target = "module:factory"`` (a policy object with
    SB3's ``predict``). Imports and runs that module's code: trusted code only."""
    if not isinstance(target, str) or target.count(":") != 1:
        raise ValueError(f"target = {target!r} must be 'module:factory'")
    module_name, attr = target.split(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # ImportError, or any error the module raises on import
        raise ValueError(
            f"target = {target!r}: cannot import {module_name!r}: {type(exc).__name__}: {exc}"
        ) from exc
    factory = getattr(module, attr, None)
    if not callable(factory):
        raise ValueError(f"target = {target!r}: {module_name} has no callable {attr!r}")
    try:
        policy = factory(obs_names, **params)
    except Exception as exc:  # the user's code: any failure is that factory's
        why = " ".join(str(exc).split()) or type(exc).__name__
        raise ValueError(
            f"target = {target!r}: {attr}(obs_names{', **params' if params else ''}) failed: "
            f"{type(exc).__name__}: {why}"
        ) from exc
    if not callable(getattr(policy, "predict", None)):
        raise ValueError(f"target = {target!r} returned {type(policy).__name__} without predict")
    return policy


def _sb3_factory(
    obs_names: Sequence[str], path: str | Path = DEFAULT_AGENT, **kwargs: Any
) -> SB3Agent:
    """Registry factory ``"sb3"``: :func:`load_sb3_policy` ``(path, obs_names, **kwargs)``."""
    return load_sb3_policy(path, obs_names, **kwargs)


register_policy("sb3", _sb3_factory, obs_mode="features+rul", family="external")
register_policy("factory", load_factory, obs_mode="features+rul", family="external")
