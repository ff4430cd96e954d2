"""Generated cases for the validated configuration classes (``from_dict`` with random input).

Keys are drawn from each class's fields plus unknown names; values from numbers in and out
of range, NaN, inf, huge integers, strings, None, booleans, lists and dicts. The contract
("clear error or valid result"): a ``ValueError``/``TypeError`` whose message names the
class and a field or key, or an object whose every given field holds a finite number inside
the declared range (equal to the given value; a boolean only for a switch, unit "bool");
never another exception.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from hypothesis import strategies as st

from scas_env.actuator import params as params_module
from scas_env.actuator.config import Validated
from scas_env.core.costs import CostModel
from scas_env.core.scenario import Scenario

GROUPS: tuple[type[Validated], ...] = tuple(
    f.type if isinstance(f.type, type) else getattr(params_module, f.type)
    for f in dataclasses.fields(params_module.ScasParams)
)
CLASSES: tuple[type[Validated], ...] = (*GROUPS, Scenario, CostModel)


def numeric_fields(cls: type[Validated]) -> dict[str, dict[str, Any]]:
    return {f.name: dict(f.metadata) for f in dataclasses.fields(cls) if "unit" in f.metadata}


def _in_range(md: dict[str, Any], draw) -> float:
    lo = md["lo"] if math.isfinite(md["lo"]) else -1e6
    hi = md["hi"] if math.isfinite(md["hi"]) else max(lo, 0.0) + 1e6
    value = draw(st.floats(lo, hi, allow_nan=False))
    return float(round(value)) if md.get("integer") else value


#: Odd values of every kind, integers beyond float range and exponent strings included.
odd_values = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**400), 10**400),
    st.sampled_from([math.nan, math.inf, -math.inf, 0, -1, 1e308, -1e308, 5e-324]),
    st.text(max_size=5),
    st.sampled_from(["1.5", "2000", "nan", "", "-7", "2e3", "1e400"]),
    st.none(),
    st.booleans(),
    st.lists(st.integers(0, 3), max_size=2),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
    st.integers(-5, 5).map(np.int64),
    st.floats(-10, 10).map(np.float32),
)


@st.composite
def config_dict(draw, cls: type[Validated]) -> dict[str, Any]:
    names = [f.name for f in dataclasses.fields(cls)]
    numeric = numeric_fields(cls)
    keys = draw(
        st.lists(
            st.one_of(st.sampled_from(names), st.text(min_size=1, max_size=6)),
            max_size=3,
            unique=True,
        )
    )
    out: dict[str, Any] = {}
    for key in keys:
        if key in numeric and draw(st.booleans()):
            out[key] = _in_range(numeric[key], draw)
        else:
            out[key] = draw(odd_values)
    return out


def check_from_dict(cls: type[Validated], data: dict[str, Any]) -> Any:
    """``cls.from_dict(data)`` under the contract of the module docstring."""
    fields_ = {f.name for f in dataclasses.fields(cls)}
    numeric = numeric_fields(cls)
    try:
        obj = cls.from_dict(data)
    except (ValueError, TypeError) as err:
        message = str(err)
        assert cls.__name__ in message, f"error does not name {cls.__name__}: {err!r}"
        assert any(name in message for name in fields_ | set(map(str, data))), (
            f"error names no field or key: {err!r}"
        )
        return err
    except Exception as err:
        raise AssertionError(
            f"{cls.__name__}.from_dict({data!r}) crashed with {type(err).__name__}: {err}"
        ) from err
    assert set(data) <= fields_, f"accepted unknown keys {sorted(set(data) - fields_)}"
    for key, given in data.items():
        if key not in numeric:
            continue
        md = numeric[key]
        if md["unit"] != "bool":  # only a switch (0/1) takes true/false
            assert not isinstance(given, bool | np.bool_), f"{key}: boolean {given!r} as number"
        stored = getattr(obj, key)
        assert isinstance(stored, int | float) and math.isfinite(stored), (key, given, stored)
        assert stored == float(given), f"{key}: given {given!r}, stored {stored!r}"
        lo_ok = stored > md["lo"] if md["lo_open"] else stored >= md["lo"]
        hi_ok = stored < md["hi"] if md["hi_open"] else stored <= md["hi"]
        assert lo_ok and hi_ok, f"{key} = {stored} outside its range"
    return obj
