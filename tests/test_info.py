"""The step info's fast deep copy (scas_env.info)."""

from __future__ import annotations

import copy
import pickle

import numpy as np

from scas_env.env import ScasMaintenanceEnv
from scas_env.info import StepInfo


def _containers(obj: object) -> list[int]:
    """ids of every container reachable from ``obj``."""
    if isinstance(obj, dict):
        return [id(obj), *(i for v in obj.values() for i in _containers(v))]
    if isinstance(obj, list | np.ndarray):
        return [id(obj)]
    return []


def test_deepcopy_is_equal_and_shares_no_container() -> None:
    info = StepInfo(a=1, b=2.5, c=None, d=StepInfo(x=1.0, y=StepInfo(z=True)), e=[1, [2]])
    clone = copy.deepcopy(info)
    assert clone == info and type(clone) is StepInfo
    assert type(clone["d"]) is StepInfo and type(clone["d"]["y"]) is StepInfo
    assert not set(_containers(clone)) & set(_containers(info))
    clone["e"][1].append(3)  # a mutable leaf is copied by copy.deepcopy
    assert info["e"] == [1, [2]]


def test_env_info_deepcopies_like_a_plain_dict_and_pickles() -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=0)
    for action in (1, 0, 2, 0, 3, 1):
        *_, info = env.step(action)
    clone = copy.deepcopy(info)
    plain = copy.deepcopy(_as_plain(info))
    assert clone == plain and _as_plain(clone) == plain
    assert not set(_containers(clone)) & set(_containers(info))
    assert pickle.loads(pickle.dumps(info)) == info


def _as_plain(d: dict) -> dict:
    return {k: _as_plain(v) if isinstance(v, dict) else v for k, v in d.items()}
