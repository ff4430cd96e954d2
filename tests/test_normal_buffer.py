"""NormalBuffer hands out exactly the normals of successive Generator calls."""

from __future__ import annotations

import numpy as np
import pytest

from scas_env.block_draws import NormalBuffer


def test_same_numbers_as_successive_generator_calls_across_refills() -> None:
    sizes = np.random.default_rng(1).integers(0, 9, 3000)
    direct = np.random.default_rng(7)
    expected = np.concatenate([direct.standard_normal(int(k)) for k in sizes])
    buf = NormalBuffer(np.random.default_rng(7), block=64)  # many refills, leftovers carried
    got = np.concatenate([buf.standard_normal(int(k)) for k in sizes])
    np.testing.assert_array_equal(got, expected)


def test_storage_can_be_rows_of_a_shared_table() -> None:
    table = np.zeros((2, 32))
    pos = np.zeros((2, 1), dtype=np.int64)
    a = NormalBuffer(np.random.default_rng(0), table[0], pos[0])
    b = NormalBuffer(np.random.default_rng(1), table[1], pos[1])
    first = a.standard_normal(3)
    assert pos[0, 0] == 3 and pos[1, 0] == 0
    np.testing.assert_array_equal(first, table[0, :3])
    np.testing.assert_array_equal(b.standard_normal(2), np.random.default_rng(1).standard_normal(2))


def test_bad_arguments_raise() -> None:
    with pytest.raises(ValueError, match="Generator"):
        NormalBuffer(np.random.RandomState(0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="block"):
        NormalBuffer(np.random.default_rng(0), block=4)
    with pytest.raises(ValueError, match="size"):
        NormalBuffer(np.random.default_rng(0), block=16).standard_normal(17)
