"""Fuzz: >= 1,000 generated cases across the prognostics entry points, the configuration
classes and the shipped data tables; each must end in a clear error or a valid result,
never a crash, a NaN or a silently accepted bad input.

Cases come from the same generators as the property tests (``tests/prognostics_cases.py``,
``tests/config_cases.py``) plus random corruptions of the calibration and surrogate tables;
Hypothesis draws which entry point each case exercises (derandomised: the same 1,200 cases
on every run).
"""

from __future__ import annotations

import math
from collections import Counter
from functools import partial
from typing import Any

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scas_env.actuator.calibration import Calibration, default_calibration
from scas_env.actuator.surrogate import SurrogateModel, default_surrogate
from tests.config_cases import CLASSES, check_from_dict, config_dict, odd_values
from tests.hardening_checks import all_finite
from tests.prognostics_cases import CASES

N_CASES = 1200

#: calibration fields and the checks a valid value must pass (independent of the class)
CAL_ARRAYS = ("crack_depth_m", "crack_rate_m_per_flight", "crack_cv_depth_m", "crack_cv")
SUR_TABLES = ("mean", "unit_std", "run_std", "crack_grid", "wear_grid")


@st.composite
def calibration_case(draw) -> tuple[str, Any]:
    data = default_calibration().to_dict()
    name = draw(st.sampled_from(sorted(data)))
    if name in CAL_ARRAYS:
        values = list(data[name])
        values[draw(st.integers(0, len(values) - 1))] = draw(odd_values)
        return name, values
    return name, draw(odd_values)


def run_calibration(case: tuple[str, Any]) -> None:
    name, value = case
    data = default_calibration().to_dict() | {name: value}
    try:
        cal = Calibration(**data)
    except (ValueError, TypeError) as err:
        assert name in str(err) or "version" in str(err), f"{name}: unclear {err!r}"
        return
    stored = getattr(cal, name)
    if name in CAL_ARRAYS:
        assert all_finite(stored) and np.all(stored >= 0), f"accepted {name} = {value}"
        assert np.all(np.diff(cal.crack_depth_m) > 0) and np.all(np.diff(cal.crack_cv_depth_m) > 0)
    elif name not in ("params_digest", "version"):
        # integers (seeds, counts) may be arbitrarily large; floats must be finite
        finite = isinstance(stored, int) or (isinstance(stored, float) and math.isfinite(stored))
        assert finite and stored >= 0, f"accepted {name} = {value!r}"


@st.composite
def surrogate_case(draw) -> tuple[str, tuple[int, ...], float]:
    name = draw(st.sampled_from(SUR_TABLES))
    shape = np.shape(getattr(default_surrogate(), name))
    where = tuple(draw(st.integers(0, n - 1)) for n in shape)
    value = draw(st.one_of(st.floats(-2, 2), st.sampled_from([math.nan, math.inf, -math.inf])))
    return name, where, value


def run_surrogate(case: tuple[str, tuple[int, ...], float]) -> None:
    name, where, value = case
    data = default_surrogate().to_dict()
    table = np.array(data[name])
    table[where] = value
    try:
        model = SurrogateModel(**(data | {name: table.tolist()}))
    except ValueError as err:
        assert name in str(err), f"{name}: unclear {err!r}"
        return
    assert all_finite(model.mean, model.unit_std, model.run_std), f"accepted {name} = {value}"
    assert np.all(model.unit_std >= 0) and np.all(model.run_std > 0)
    for grid in (model.crack_grid, model.wear_grid):
        assert grid[0] == 0 and grid[-1] == 1 and np.all(np.diff(grid) > 0)
    assert all_finite(model.tables_at(0.3, 0.7))


ENTRY_POINTS: list[tuple[str, st.SearchStrategy, Any]] = [
    *((name, strategy, runner) for name, (strategy, runner) in sorted(CASES.items())),
    *((cls.__name__, config_dict(cls), partial(check_from_dict, cls)) for cls in CLASSES),
    ("calibration", calibration_case(), run_calibration),
    ("surrogate", surrogate_case(), run_surrogate),
]


def test_fuzz_clear_error_or_valid_result() -> None:
    counts: Counter[str] = Counter()

    @settings(
        max_examples=N_CASES,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(st.data())
    def check(data: st.DataObject) -> None:
        k = data.draw(st.integers(0, len(ENTRY_POINTS) - 1), label="entry point")
        name, strategy, runner = ENTRY_POINTS[k]
        runner(data.draw(strategy, label=name))
        counts[name] += 1

    check()
    assert sum(counts.values()) >= 1000, counts
    assert set(counts) == {name for name, _, _ in ENTRY_POINTS}, counts
