"""Property-based tests of the prognostics entry points (Hypothesis, derandomised).

Every entry point of ``tests/prognostics_cases.py``, fed random arrays (NaN, inf, huge,
empty, mis-shaped) and random sizes: a clear error or a finite result consistent with the
inputs, never a crash, a NaN or a silently accepted bad input.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from tests.prognostics_cases import CASES

PROPERTY_SETTINGS = settings(
    max_examples=40,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    database=None,
)


@pytest.mark.parametrize("name", sorted(CASES))
def test_clear_error_or_valid_result(name: str) -> None:
    strategy, runner = CASES[name]

    @PROPERTY_SETTINGS
    @given(strategy)
    def check(case: object) -> None:
        runner(case)

    check()
