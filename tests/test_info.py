"""The step info (``scas_env.core.info``): one implementation for one actuator and for a
batch, a fast exact deep copy."""

from __future__ import annotations

import copy
import pickle

import numpy as np

from scas_env.core.info import StepInfo, build_info
from scas_env.env import ScasMaintenanceEnv
from scas_env.vector_env import ScasMaintenanceVectorEnv


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


def _leaves(d: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in d.items():
        out.update(_leaves(v, f"{prefix}{k}.") if isinstance(v, dict) else {prefix + k: v})
    return out


def test_one_row_and_all_rows_are_the_same_info() -> None:
    """``build_info(batch, e)`` (Python scalars, the single env's) equals entry ``e`` of
    ``build_info(batch)`` (arrays, the vector env's), key for key, after tests, failures,
    replacements and downtime; the scalars are plain Python numbers."""
    venv = ScasMaintenanceVectorEnv(3, initial_health="random")
    venv.reset(seed=1)
    rng = np.random.default_rng(0)
    for _ in range(500):
        venv.step(rng.choice(4, size=3, p=[0.93, 0.06, 0.005, 0.005]))
        every = _leaves(build_info(venv.batch))
        for e in range(3):
            one = _leaves(build_info(venv.batch, e))
            assert one.keys() == every.keys()
            for key, value in one.items():
                assert type(value) in (int, float, bool), key
                assert value == every[key][e] or (np.isnan(value) and np.isnan(every[key][e]))
    a = venv.a
    assert a["failures"].sum() >= 1 and a["replacements"].sum() > a["failures"].sum()
    assert a["no_go_count"].sum() >= 1
