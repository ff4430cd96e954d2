"""AgeingRul: the RUL summary of a frozen cloud after k more steps, against direct computation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from prognostics.degradation_models import paris_crack_model
from prognostics.rul import RulPredictor, weighted_quantile
from prognostics.rul_ageing import AgeingRul, _build, sorting_order


def _sample(seed: int = 0, n: int = 600) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    r = rng.gamma(2.0, 300.0, n)
    r[:25] = 0.0  # particles already past the threshold
    return r, rng.random(n)


@pytest.mark.parametrize("k", [0.0, 1.0, 37.0, 250.0, 5000.0])
def test_matches_the_shifted_sample_computed_directly(k: float) -> None:
    r, w = _sample()
    dist = AgeingRul(r, w, low_quantile=0.05)
    shifted = np.maximum(r - k, 0.0)
    wn = w / w.sum()
    assert dist.mean(k) == pytest.approx(float(wn @ shifted), rel=1e-12, abs=1e-9)
    assert dist.low(k) == float(weighted_quantile(shifted, w, 0.05))
    for h in (0.0, 10.0, 100.0, 1e4):
        assert dist.prob_failure(k, h) == pytest.approx(float(wn[shifted <= h].sum()), abs=1e-12)


def test_equals_the_rul_predictor_after_noise_free_exact_steps() -> None:
    # a Paris-like cloud predicted k steps without noise (exact scheme) has RUL R_i - k
    depth = np.linspace(1e-4, 1e-3, 50)
    model = paris_crack_model(depth, 1e-7 * (depth / 1e-4) ** 1.1, scheme="exact")
    rng = np.random.default_rng(3)
    x = rng.uniform(1e-4, 4e-4, 400)
    log_theta = rng.normal(0.0, 0.3, 400)
    w = rng.random(400)
    pred = RulPredictor(model, 1e-3, 400, horizon_steps=20.0, low_quantile=0.1)
    dist = AgeingRul(pred.values(x, log_theta), w, low_quantile=0.1)
    for k in (0, 5, 60, 700):
        xk = x.copy()
        lt = log_theta.copy()
        if k:
            model.predict(xk, lt, float(k), rng)  # noise-free model: rng unused
        s = pred.summary(xk, lt, w)
        assert dist.mean(k) == pytest.approx(s.mean, rel=1e-6)
        assert dist.low(k) == pytest.approx(s.low, rel=1e-6, abs=1e-6)
        # R_i - k and the recomputed RUL differ by rounding only: at most a particle lying
        # exactly on the horizon can change side
        assert dist.prob_failure(k, 20.0) == pytest.approx(s.prob_failure, abs=w.max() / w.sum())


def test_from_cloud_and_summary_are_the_same_numbers() -> None:
    """The fused paths equal RulPredictor.values + AgeingRul and mean/low/prob_failure."""
    depth = np.linspace(1e-4, 1e-3, 50)
    model = paris_crack_model(depth, 1e-7 * (depth / 1e-4) ** 1.1, scheme="exact")
    rng = np.random.default_rng(8)
    x = rng.uniform(5e-5, 1.1e-3, 500)  # below the grid, inside, beyond the threshold
    log_theta = rng.normal(0.0, 0.4, 500)
    w = rng.random(500)
    pred = RulPredictor(model, 1e-3, 500, horizon_steps=20.0, low_quantile=0.1)
    ref = AgeingRul(pred.values(x, log_theta), w, low_quantile=0.1)
    fused = AgeingRul.from_cloud(pred, x, log_theta, w, low_quantile=0.1)
    for a, b in zip(ref.tables(), fused.tables(), strict=True):
        assert np.array_equal(a, b)
    for k in (0.0, 3.0, 250.0, 1e5):
        for h in (0.0, 20.0):
            assert fused.summary(k, h) == (ref.mean(k), ref.low(k), ref.prob_failure(k, h))
    with pytest.raises(ValueError, match=r"log_theta must be an array of shape \(500,\)"):
        AgeingRul.from_cloud(pred, x, log_theta[:-1], w, low_quantile=0.1)
    with pytest.raises(ValueError, match="weights"):
        AgeingRul.from_cloud(pred, x, log_theta, np.zeros(500), low_quantile=0.1)
    with pytest.raises(ValueError, match="horizon"):
        fused.summary(0.0, np.nan)


def test_doc_numbers_by_hand() -> None:
    dist = AgeingRul(np.array([10.0, 30.0, 50.0]), np.array([0.25, 0.25, 0.5]), low_quantile=0.3)
    assert dist.mean(0.0) == pytest.approx(35.0)
    assert dist.mean(20.0) == pytest.approx(0.25 * 10.0 + 0.5 * 30.0)
    assert dist.low(0.0) == 30.0 and dist.low(40.0) == 0.0
    assert dist.prob_failure(15.0, 10.0) == pytest.approx(0.25)
    assert dist.prob_failure(25.0, 10.0) == pytest.approx(0.5)


def test_bad_inputs_raise() -> None:
    with pytest.raises(ValueError, match="weights"):
        AgeingRul(np.ones(3), np.zeros(3), low_quantile=0.1)
    with pytest.raises(ValueError, match=r"rul must be .*>= 0, got -1.0"):
        AgeingRul(np.array([1.0, -1.0]), np.ones(2), low_quantile=0.1)
    with pytest.raises(ValueError, match="low_quantile"):
        AgeingRul(np.ones(2), np.ones(2), low_quantile=1.5)
    with pytest.raises(ValueError, match=r"weights must be an array of shape \(2,\)"):
        AgeingRul(np.ones(2), np.ones(3), low_quantile=0.1)
    with pytest.raises(ValueError, match="horizon"):
        AgeingRul(np.ones(2), np.ones(2), low_quantile=0.1).prob_failure(0.0, -1.0)


_RUL_VALUES = st.one_of(
    st.just(0.0), st.just(-0.0), st.just(1e300), st.floats(0.0, 1e6, allow_subnormal=True)
)


@settings(max_examples=300, deadline=None)
@given(st.lists(_RUL_VALUES, min_size=1, max_size=600))
def test_the_radix_order_is_numpys_stable_argsort(values: list[float]) -> None:
    r = np.array(values)
    assert sorting_order(r).tolist() == np.argsort(r, kind="stable").tolist()


def _tables_by_quicksort(r: np.ndarray, w: np.ndarray, level: float) -> tuple:
    """What ``_build`` gave on ``np.argsort``'s quicksort order: the same loops, in Python."""
    order = np.argsort(r)
    total = 0.0  # summed in order, as _build
    for v in w:
        total += v
    n = r.size
    sorted_r, cum, sw, swr = r[order], np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1)
    for j in range(n):
        cum[j + 1] = cum[j] + w[order[j]] / total
    for j in range(n - 1, -1, -1):
        wk = w[order[j]] / total
        sw[j] = sw[j + 1] + wk
        swr[j] = swr[j + 1] + wk * sorted_r[j]
    q = next((sorted_r[j] for j in range(n) if cum[j + 1] >= level), sorted_r[-1])
    return sorted_r, cum, sw, swr, q


@pytest.mark.parametrize("ties", [False, True])
def test_the_tables_are_the_quicksorts_bit_for_bit(ties: bool) -> None:
    """Equal RULs with equal weights (resampled copies of a particle) or no ties: the
    tables are those of a quicksort-ordered build, bit for bit (the order of equal
    values cannot change a sum when their weights are equal too)."""
    rng = np.random.default_rng(11)
    r, w = _sample(seed=11, n=400)  # 25 zeros, weights random
    w[:25] = 0.0  # past the threshold: conditioned away
    if ties:  # 80 copies of 20 particles, each copy with its particle's RUL and weight
        r[100:180], w[100:180] = np.repeat(r[200:220], 4), np.repeat(w[200:220], 4)
    rng.shuffle(idx := np.arange(r.size))
    r, w = r[idx], w[idx]
    n = r.size
    out = [np.empty(n), np.empty(n + 1), np.empty(n + 1), np.empty(n + 1)]
    status, q = _build(r, w, 0.05, *out)
    assert status == 0
    expected = _tables_by_quicksort(r, w, 0.05)
    for got, want in zip([*out, q], expected, strict=True):
        np.testing.assert_array_equal(got, want)
