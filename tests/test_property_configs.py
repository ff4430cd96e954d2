"""Property-based tests of the validated configuration classes (Hypothesis, derandomised).

Every parameter group of ``ScasParams``, ``Scenario`` and ``CostModel`` built with
``from_dict`` from random keys and values: a ValueError/TypeError naming the class and a
field, or an object holding exactly the given finite, in-range values; never another
exception (see ``tests/config_cases.py``).
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from tests.config_cases import CLASSES, check_from_dict, config_dict

PROPERTY_SETTINGS = settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
    database=None,
)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_from_dict_gives_a_clear_error_or_the_given_values(cls: type) -> None:
    @PROPERTY_SETTINGS
    @given(config_dict(cls))
    def check(data: dict) -> None:
        check_from_dict(cls, data)

    check()


def test_an_integer_beyond_float_range_is_a_clear_error() -> None:
    from scas_env.core.costs import CostModel

    check_from_dict(CostModel, {"flight_value_usd": 10**400})


def test_an_exponent_string_for_an_integer_field_is_handled() -> None:
    from scas_env.core.scenario import Scenario

    check_from_dict(Scenario, {"episode_slots": "2e3"})
