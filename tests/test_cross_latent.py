"""The latent cross-fault error (``Scenario.cross_error_memory_flights``): each particle's
score follows the stated AR(1) on the filter stream's own normals, the likelihood reads the
other part at the particle's own view of it (and is the variance model's with nothing added
when the scores are 0), the option is refused where it cannot work, the default is
untouched, and the single and vector envs stay equal bit for bit with it."""

from __future__ import annotations

import math
import pickle

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from prognostics.normals import NormalStream
from scas_env.core.filters import advance_scores, effect_likelihood, latent_effect_likelihood
from scas_env.core.scenario import Scenario

LATENT = {"cross_error_memory_flights": 250.0}


def test_scores_follow_the_ar1_on_the_streams_own_normals() -> None:
    """``s <- r s + sqrt(1 - r^2) eps`` with ``r = exp(-d / memory)`` and ``eps`` the
    Generator's own next normals, exactly; after many steps the scores are N(0, 1) with the
    stated lag correlation (independent check of the recursion)."""
    score = np.linspace(-2.0, 2.0, 50)
    start = score.copy()
    stream = NormalStream(np.random.default_rng(5))
    advance_scores(score, 7.0, 250.0, stream.handle)
    r = math.exp(-7.0 / 250.0)
    eps = np.random.default_rng(5).standard_normal(50)
    np.testing.assert_array_equal(score, r * start + math.sqrt(1.0 - r * r) * eps)

    many = np.zeros(20_000)
    lagged = None
    for step in range(60):
        advance_scores(many, 10.0, 250.0, stream.handle)
        if step == 49:
            lagged = many.copy()
    assert many.std() == pytest.approx(1.0, abs=0.02)
    corr = np.corrcoef(lagged, many)[0, 1]
    assert corr == pytest.approx(math.exp(-100.0 / 250.0), abs=0.02)


def _tables(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    own, other = np.linspace(0.0, 1.0, 6), np.linspace(0.0, 1.0, 5)
    stack = np.stack([
        rng.normal(size=(6, 5)), 0.5 + rng.random((6, 5)), 0.2 + rng.random((6, 5)),
    ])  # fmt: skip
    return stack, own, other


def _work(n: int) -> tuple:
    return tuple(np.empty(n) for _ in range(13))


def test_the_likelihood_reads_each_particles_own_view_of_the_other_part() -> None:
    """Per particle, the latent likelihood is the variance model's for that particle alone
    at ``other + sd score`` with no variance added; with all scores 0 it is the variance
    model's with ``extra_var = 0`` for the whole cloud, bit for bit."""
    rng = np.random.default_rng(2)
    stack, own, other_grid = _tables(rng)
    n = 8
    x = rng.random(n) * 1e-3
    w = np.full(n, 1.0 / n)
    score = rng.normal(size=n)
    zm, zv = rng.normal(size=n), 0.5 + rng.random(n)
    lat_zm, lat_zv, lat_ll = zm.copy(), zv.copy(), np.empty(n)
    latent_effect_likelihood(0.3, 4.0, x, w, 1e-3, stack, own, other_grid, 0.4, 0.1, score,
                             1.0, lat_zm, lat_zv, lat_ll, _work(n))  # fmt: skip
    for i in range(n):
        one_zm, one_zv, one_ll = zm[i : i + 1].copy(), zv[i : i + 1].copy(), np.empty(1)
        view = min(max(0.4 + 0.1 * score[i], 0.0), 1.0)
        effect_likelihood(0.3, 4.0, x[i : i + 1], np.ones(1), 1e-3, stack, own, other_grid,
                          view, 1.0, 0.0, one_zm, one_zv, one_ll, _work(1))  # fmt: skip
        assert lat_ll[i] == one_ll[0] and lat_zm[i] == one_zm[0] and lat_zv[i] == one_zv[0]
    a_zm, a_zv, a_ll = zm.copy(), zv.copy(), np.empty(n)
    b_zm, b_zv, b_ll = zm.copy(), zv.copy(), np.empty(n)
    shift_a = latent_effect_likelihood(0.3, 4.0, x, w, 1e-3, stack, own, other_grid, 0.4, 0.1,
                                       np.zeros(n), 1.0, a_zm, a_zv, a_ll, _work(n))  # fmt: skip
    shift_b = effect_likelihood(0.3, 4.0, x, w, 1e-3, stack, own, other_grid, 0.4, 1.0, 0.0,
                                b_zm, b_zv, b_ll, _work(n))  # fmt: skip
    assert shift_a == shift_b
    np.testing.assert_array_equal(a_ll, b_ll)
    np.testing.assert_array_equal(a_zm, b_zm)


def test_the_option_is_refused_where_it_cannot_work() -> None:
    with pytest.raises(ValueError, match="cross_variance_inflation must be 1"):
        Scenario(cross_error_memory_flights=250.0, cross_variance_inflation=50.0)
    with pytest.raises(ValueError, match="rejuvenation must be 'none'"):
        Scenario(cross_error_memory_flights=250.0, rejuvenation="resample_move")
    with pytest.raises(ValueError, match="cross_error_memory_flights"):
        Scenario(cross_error_memory_flights=-1.0)


def test_the_default_has_no_score_row_and_the_option_one() -> None:
    default = gym.make(scas_env.ENV_ID).unwrapped
    latent = gym.make(scas_env.ENV_ID, scenario=Scenario(**LATENT)).unwrapped
    assert latent.batch.a["aux"].shape[2] == default.batch.a["aux"].shape[2] + 1
    assert latent.setup.filters.cross_row == default.batch.a["aux"].shape[2]


def test_single_and_vector_envs_agree_with_the_option_also_after_pickling() -> None:
    """Two actuators of the vector env against single envs seeded alike, random actions
    with tests and replacements, bit for bit; a single env pickled mid-episode continues
    the same episode."""
    scenario = Scenario(**LATENT)
    venv = gym.make_vec(scas_env.ENV_ID, num_envs=2, vectorization_mode="vector_entry_point",
                        scenario=scenario)  # fmt: skip
    singles = [gym.make(scas_env.ENV_ID, scenario=scenario) for _ in range(2)]
    vobs, _ = venv.reset(seed=40)
    sobs = [env.reset(seed=40 + k)[0] for k, env in enumerate(singles)]
    rng = np.random.default_rng(1)
    for step in range(250):
        act = rng.choice(4, size=2, p=[0.8, 0.15, 0.03, 0.02])
        vobs, vr, _, _, _ = venv.step(act)
        for k, env in enumerate(singles):
            sobs[k], r, *_ = env.step(int(act[k]))
            np.testing.assert_array_equal(vobs[k], sobs[k])
            assert vr[k] == r
        if step == 120:
            copy = pickle.loads(pickle.dumps(singles[0]))
            tail = [int(a) for a in rng.choice(4, size=60, p=[0.8, 0.15, 0.03, 0.02])]
            a_obs = [singles[0].unwrapped.step(a)[0] for a in tail]
            b_obs = [copy.unwrapped.step(a)[0] for a in tail]
            np.testing.assert_array_equal(np.array(a_obs), np.array(b_obs))
            break
