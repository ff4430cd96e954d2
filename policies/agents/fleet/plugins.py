"""Trained fleet agents as benchmark policies: the centralised and the parameter-shared PPO.

:class:`FleetAgent` acts on **raw** flat ``ScasFleet-v0`` observations ``(B, D)`` (the
project's policy protocol): it rebuilds the action masks from the observation
(:meth:`policies.agents.fleet.masks.FleetObsLayout.masks`, equal to the env's), normalises with
the agent's frozen ``VecNormalize`` statistics and asks the MaskablePPO network for

* ``kind = "joint"`` (the centralised agent,
  :class:`~experiments.fleet_agents.adapters.FleetVecEnv`): the fleet's whole
  ``MultiDiscrete`` action from the fleet's observation;
* ``kind = "shared"`` (one network for every aircraft,
  :class:`~experiments.fleet_agents.shared_adapter.FleetAgentsVecEnv`): each aircraft's row
  from its own view, the rows joined into the fleet's action.

:func:`load_fleet_agent` reads ``<stem>.zip`` (MaskablePPO), ``<stem>_normalization.json`` (the
observation statistics, :class:`policies.agents.obs_normalization.ObsNormalization`) and
``<stem>.json`` (kind, the observation names it was trained on, the per-aircraft view's
options, whether the scenario tests before every flight) and checks the model's observation and
action spaces against the env's before it acts, with an error that says what differs. The
observation does not tell the env's ``Scenario.preflight``, on which the masks depend: given
(``preflight=``), an agent trained on the other one is refused. Registered for the benchmark:
``"fleet_ppo"`` (default: the shipped :data:`FLEET_JOINT_AGENT`) and ``"fleet_shared_ppo"``
(:data:`FLEET_SHARED_AGENT`), both with ``params={"path": ..., "preflight": ...}``.

**Nothing is unpickled**, as for the single-actuator agent (:mod:`policies.agents.sb3_agents`):
the network is rebuilt from the zip's JSON ``data`` and its ``policy.pth`` tensors
(``torch.load(weights_only=True)``), the statistics come from JSON. A zip whose network needs
pickled objects, or a ``*_vecnormalize.pkl`` without its JSON twin, is refused (convert a
trusted pickle once with :func:`policies.agents.obs_normalization.convert_vecnormalize`). The
shipped files are checked against the package's SHA-256 manifest first, and the zip's weights
against the ``weights_sha256`` its metadata records.

Randomness, as for the single-actuator agents: ``deterministic=True`` (the benchmark's) draws
nothing; ``deterministic=False`` samples from the agent's own torch stream
(:class:`policies.agents.policy_random.PolicyRandom`), never from the process-global
generators, and ``reset(seed)`` re-seeds that stream only (a batch's seeds: the first seeds
the one stream the whole batch shares).
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from policies.agents.agent_files import (
    LoadedModel,
    NeedsPickle,
    build_policy,
    read_json_file,
    read_zip,
    weights_sha256,
)
from policies.agents.fleet.masks import FleetObsLayout
from policies.agents.obs_normalization import ObsNormalization
from policies.agents.policy_random import PolicyRandom
from policies.agents.sb3_agents import DATA_DIR, check_manifest
from policies.base import check_finite, register_policy
from scas_env.core.scenario import PREFLIGHT
from scas_env.utils.atomic_file import write_text_atomic

__all__ = [
    "FLEET_JOINT_AGENT",
    "FLEET_SHARED_AGENT",
    "KINDS",
    "FleetAgent",
    "load_fleet_agent",
    "write_agent_meta",
]

FLEET_JOINT_AGENT = DATA_DIR / "fleet_maskable_ppo.zip"
FLEET_SHARED_AGENT = DATA_DIR / "fleet_shared_ppo.zip"
#: ``joint``: one network over the fleet; ``shared``: one network per aircraft row
KINDS = ("joint", "shared")


class FleetAgent:
    """A MaskablePPO fleet agent on raw flat fleet observations (module docstring).

    Parameters
    ----------
    model : the MaskablePPO model.
    normalizer : ``VecNormalize`` whose ``obs_rms`` scales the network's input, or ``None``.
    obs_names : the fleet env's observation names.
    kind : ``"joint"`` or ``"shared"``.
    agent_id, fleet_status : the shared agent's view (:class:`FleetAgentsVecEnv`'s options).
    tests_every_flight : the scenario tests before every flight (the masks' rule).
    """

    def __init__(
        self,
        model: Any,
        normalizer: Any,
        obs_names: Sequence[str],
        *,
        kind: str = "joint",
        agent_id: bool = True,
        fleet_status: bool = True,
        tests_every_flight: bool = False,
    ) -> None:
        if kind not in KINDS:
            raise ValueError(f"kind = {kind!r} must be one of {KINDS}")
        self.model, self.normalizer, self.kind = model, normalizer, kind
        self.rng = PolicyRandom()
        self.obs_names = tuple(obs_names)
        self.layout = lay = FleetObsLayout(self.obs_names, tests_every_flight=tests_every_flight)
        self.agent_id, self.fleet_status = bool(agent_id), bool(fleet_status)
        if kind == "joint":
            want_obs, want_nvec = len(self.obs_names), np.tile(lay.nvec, lay.n)
        else:
            want_obs = lay.agent_size(agent_id=self.agent_id, fleet_status=self.fleet_status)
            want_nvec = lay.nvec
        got_obs = tuple(model.observation_space.shape)
        got_nvec = np.asarray(getattr(model.action_space, "nvec", []))
        if got_obs != (want_obs,) or not np.array_equal(got_nvec, want_nvec):
            raise ValueError(
                f"the {kind} agent observes {got_obs} and chooses {got_nvec.tolist()}; this fleet "
                f"({lay.n} aircraft x {lay.a} actuators, {lay.k} mission types) gives "
                f"({want_obs},) and needs {want_nvec.tolist()}: it was trained on another fleet"
            )

    def network_input(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The network's (normalised) input rows and their masks for observations (B, D)."""
        masks = self.layout.masks(obs)
        if self.kind == "joint":
            rows = np.asarray(obs, dtype=np.float32)
        else:
            views = self.layout.agent_obs(
                obs, agent_id=self.agent_id, fleet_status=self.fleet_status
            )
            rows = views.reshape(-1, views.shape[-1])
            masks = masks.reshape(rows.shape[0], -1)
        if self.normalizer is not None:
            rows = self.normalizer.normalize_obs(rows).astype(np.float32)
        return rows, masks

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """The fleet's action (N (1 + A),) for one observation, (B, N (1 + A)) for a batch.
        ``ValueError`` for another shape or a non-finite entry (:func:`check_finite`)."""
        obs = np.asarray(observation, dtype=np.float32)
        n = len(self.obs_names)
        if obs.ndim not in (1, 2) or obs.shape[-1] != n:
            raise ValueError(f"observation has shape {obs.shape}; expected ({n},) or (n_envs, {n})")
        check_finite(obs, self.obs_names)  # the env saturates at finite bounds: a NaN is a bug
        single = obs.ndim == 1
        batch = np.atleast_2d(obs)
        rows, masks = self.network_input(batch)
        if deterministic:
            actions, _ = self.model.predict(rows, deterministic=True, action_masks=masks)
        else:  # MaskablePPO samples from torch's global generator: run it on the agent's own
            with self.rng.torch_stream():
                actions, _ = self.model.predict(rows, deterministic=False, action_masks=masks)
        out = np.asarray(actions, dtype=np.int64).reshape(batch.shape[0], -1)
        return (out[0] if single else out), state

    def reset(self, seed: int | Sequence[int] | None = None) -> None:
        """New episodes. ``seed`` re-seeds the agent's own stream for reproducible
        ``deterministic=False`` actions (the global generators are left alone): an ``int``, or
        a batch's seeds, one per fleet, of which the first seeds the one stream the batch
        shares (the network samples every row at once). ``None`` keeps the stream running."""
        if seed is not None:
            self.rng.seed(seed)


def write_agent_meta(path: Path, meta: dict[str, Any]) -> None:
    """``<stem>.json`` beside the zip ``path`` (what :func:`load_fleet_agent` reads), written
    atomically (a reader never sees half a file)."""
    stem = path.name.removesuffix(".zip")
    text = json.dumps(meta, indent=2, sort_keys=True) + "\n"
    write_text_atomic(path.with_name(f"{stem}.json"), text)


def _ints(entry: Any) -> list[int]:
    """The integers of a space's JSON entry (``"[7 4 4]"``, ``"[555]"`` or a list)."""
    if isinstance(entry, list):
        return [int(v) for v in entry]
    return [int(v) for v in re.findall(r"-?\d+", entry)] if isinstance(entry, str) else []


def read_fleet_policy(path: Path, obs_size: int, nvec: np.ndarray) -> LoadedModel:
    """The MaskablePPO network of ``path`` for a ``Box(obs_size,)`` observation and a
    ``MultiDiscrete(nvec)`` action, rebuilt without unpickling (module docstring)."""
    import gymnasium as gym

    data, blob = read_zip(path)
    action = data.get("action_space")
    got = _ints(action.get("nvec") if isinstance(action, dict) else None)
    obs = data.get("observation_space")
    shape = _ints(obs.get("_shape") if isinstance(obs, dict) else None)
    if list(shape) != [obs_size] or list(got) != [int(v) for v in nvec]:
        raise ValueError(
            f"{path}: the agent observes {tuple(shape)} and chooses {list(got)}; this fleet "
            f"gives ({obs_size},) and needs {[int(v) for v in nvec]}: it was made for another "
            "fleet"
        )
    obs_space = gym.spaces.Box(-np.inf, np.inf, shape=(obs_size,), dtype=np.float32)
    action_space = gym.spaces.MultiDiscrete(np.asarray(nvec, dtype=np.int64))
    try:
        return build_policy(path, data, blob, obs_space, action_space)
    except NeedsPickle as exc:
        raise ValueError(f"{path}: cannot be read without unpickling: {exc}") from None


def load_fleet_agent(
    path: str | Path,
    obs_names: Sequence[str],
    *,
    kind: str | None = None,
    preflight: str | None = None,
) -> FleetAgent:
    """The fleet agent of ``path`` (``.zip`` with ``_normalization.json`` and ``.json`` beside
    it) for an env with ``obs_names``; nothing is unpickled (module docstring).

    ``preflight``: the env's ``Scenario.preflight``; an agent whose metadata says it was
    trained on the other one (``tests_every_flight``) raises ``ValueError``, since its masks
    would differ from the env's. ``None``: not checked (the metadata's masks are used)."""
    if preflight is not None and preflight not in PREFLIGHT:
        raise ValueError(f"preflight = {preflight!r} must be None or one of {PREFLIGHT}")
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"path = {str(path)!r} does not exist (expected a fleet agent's .zip)")
    check_manifest(path)
    stem = path.name.removesuffix(".zip")
    meta_path = path.with_name(f"{stem}.json")
    if not meta_path.is_file():
        raise ValueError(f"{path}: its metadata {meta_path.name} is missing (kind, obs_names)")
    check_manifest(meta_path)
    meta = read_json_file(meta_path, "fleet agent metadata file")
    if not isinstance(meta, dict):
        raise ValueError(f"{meta_path}: not an agent metadata file (expected a JSON object)")
    kind = kind if kind is not None else meta.get("kind", "joint")
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} must be one of {KINDS}")
    trained = tuple(meta.get("obs_names", ()))
    names = tuple(obs_names)
    if trained and names != trained:
        diff = sorted(set(trained) ^ set(names))[:4]
        if diff:
            what = f"first differences: {diff}"
        else:  # the same names in another order
            k = next(i for i, (x, y) in enumerate(zip(trained, names, strict=False)) if x != y)
            what = f"the same names in another order: entry {k} is {names[k]!r}, trained on "
            what += f"{trained[k]!r}"
        raise ValueError(
            f"{path}: trained on a fleet observation of {len(trained)} entries, this env gives "
            f"{len(names)} ({what}): another fleet configuration"
        )
    recorded = meta.get("weights_sha256")
    if recorded is not None and recorded != weights_sha256(path):
        raise ValueError(f"{path}: its weights differ from the weights_sha256 of {meta_path.name}")
    every_flight = bool(meta.get("tests_every_flight", False))
    if preflight is not None and every_flight != (preflight == "every_flight"):
        trained = "every_flight" if every_flight else "on_demand"
        raise ValueError(
            f"{path}: trained with preflight = {trained!r} (tests_every_flight = "
            f"{every_flight} in {meta_path.name}), this env's preflight is {preflight!r}: "
            "its action masks (plain flying of an aircraft a failed test holds) would differ "
            "from the env's; use an agent trained on this preflight"
        )
    agent_id = bool(meta.get("agent_id", True))
    fleet_status = bool(meta.get("fleet_status", True))
    lay = FleetObsLayout(obs_names)
    if kind == "joint":
        obs_size, nvec = len(tuple(obs_names)), np.tile(lay.nvec, lay.n)
    else:
        obs_size = lay.agent_size(agent_id=agent_id, fleet_status=fleet_status)
        nvec = lay.nvec
    model = read_fleet_policy(path, obs_size, nvec)
    norm_path = path.with_name(f"{stem}_normalization.json")
    normalizer = None
    if norm_path.is_file():
        check_manifest(norm_path)
        normalizer = ObsNormalization.load(norm_path)
        if normalizer.size != obs_size:
            raise ValueError(
                f"{norm_path}: statistics of {normalizer.size} entries, the network reads "
                f"{obs_size}"
            )
    elif meta.get("normalize", True):
        pkl = path.with_name(f"{stem}_vecnormalize.pkl")
        hint = (
            f" ({pkl.name} is a pickle: convert a trusted one with "
            "policies.agents.obs_normalization.convert_vecnormalize)"
            if pkl.is_file()
            else ""
        )
        raise ValueError(f"{path}: trained with VecNormalize but {norm_path.name} is missing{hint}")
    return FleetAgent(
        model,
        normalizer,
        obs_names,
        kind=kind,
        agent_id=agent_id,
        fleet_status=fleet_status,
        tests_every_flight=every_flight,
    )


def _joint_factory(
    obs_names: Sequence[str], path: str | Path = FLEET_JOINT_AGENT, preflight: str | None = None
) -> FleetAgent:
    """Registry factory ``"fleet_ppo"``: the shipped centralised agent or ``path``
    (``preflight``: the env's, checked against the agent's; :func:`load_fleet_agent`)."""
    return load_fleet_agent(path, obs_names, preflight=preflight)


def _shared_factory(
    obs_names: Sequence[str], path: str | Path | None = None, preflight: str | None = None
) -> FleetAgent:
    """Registry factory ``"fleet_shared_ppo"``: the shipped parameter-shared agent or
    ``path`` (``preflight``: as ``"fleet_ppo"``'s)."""
    if path is None:
        path = FLEET_SHARED_AGENT
        if not path.is_file():
            raise ValueError(
                "fleet_shared_ppo: no parameter-shared fleet agent is shipped; pass "
                'params={"path": ".../ckpt_<n>.zip"} (docs/fleet_agents.md)'
            )
    return load_fleet_agent(path, obs_names, preflight=preflight)


register_policy("fleet_ppo", _joint_factory, obs_mode="features+rul", family="external")
register_policy("fleet_shared_ppo", _shared_factory, obs_mode="features+rul", family="external")
