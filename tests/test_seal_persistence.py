"""``Scenario(seal_cross_persistence=rho)``: each seal particle carries the spring estimate's
error as a standard-normal offset, AR(1) with ``rho`` per flight, and reads its features at
its own spring value (docs/beliefs.md, cross-fault errors)."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.belief_calibration import policy_action
from prognostics.resampling import systematic_resample
from scas_env.core.filters import (
    _effect_update,
    _moments,
    effect_likelihood,
    predict_filter,
    work_arrays,
)
from scas_env.core.parts import learn_now, replace_part, reset_filter
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv
from tests.option_lockstep import run_option_lockstep

RHO = 0.99


def _env(**kw: object) -> ScasMaintenanceEnv:
    env = ScasMaintenanceEnv(seal_cross_persistence=RHO, n_particles=200, **kw)
    env.reset(seed=3)
    for t in range(40):
        env.step(policy_action("test10", t))
    return env


def _twin(rng: np.random.Generator) -> np.random.Generator:
    """A generator at ``rng``'s state (draws what ``rng`` will draw next)."""
    twin = np.random.Generator(type(rng.bit_generator)())
    twin.bit_generator.state = rng.bit_generator.state
    return twin


def test_a_prediction_moves_the_offsets_as_an_ar1_of_the_flights() -> None:
    """Over d flights each offset becomes rho^d u + sqrt(1 - rho^2d) z, z the filter
    stream's next normals: the residuals, rescaled, are a contiguous run of the normals a
    copy of the stream draws (after the process's own), to rounding."""
    env = _env()
    a, batch = env.batch.a, env.batch
    row = batch.setup.filters.persistence[1]
    u0 = a["aux"][0, 1, row].copy()
    rng = batch.rngs[0]["filter"]
    twin = _twin(rng)
    d = 7.0
    a["pending"][0, 1] = d
    work = work_arrays(u0.size, len(batch.setup.learn_cols))
    handle = tuple(int(h) for h in a["h_filter"][0])
    predict_filter(0, 1, d, batch.bank, a["pending"], a["status"], work, batch.setup.filters,
                   handle)  # fmt: skip
    keep = RHO**d
    z = (a["aux"][0, 1, row] - keep * u0) / np.sqrt(1.0 - keep * keep)
    drawn = twin.standard_normal(4 * u0.size)
    starts = [k for k in range(3 * u0.size + 1) if np.allclose(drawn[k : k + u0.size], z)]
    assert len(starts) == 1, "the offsets are not the AR(1) step of the stream's normals"
    # and the wrong persistence is caught: rho (one flight) in place of rho^d
    z_wrong = (a["aux"][0, 1, row] - RHO * u0) / np.sqrt(1.0 - RHO * RHO)
    assert not any(np.allclose(drawn[k : k + u0.size], z_wrong) for k in range(3 * u0.size))


def test_at_one_spring_value_it_is_the_likelihood_without_extra_variance() -> None:
    """Every particle at its own spring value, all equal: the shared value's likelihood
    with no added variance, bit for bit (effect beliefs, log-likelihoods, shift); at
    different values, not."""
    rng = np.random.default_rng(0)
    n = 64
    grid = np.linspace(0.0, 1.0, 5)
    stack = rng.random((3, 5, 5)) + 0.5
    x, w = rng.random(n) * 1e-5, rng.dirichlet(np.ones(n))
    args = (0.9, 3.0, x, w, 2e-5, stack, grid, grid, 0.37, 1.0, 0.0)
    outs = []
    for others in (np.empty(0), np.full(n, 0.37), np.linspace(0.0, 1.0, n)):
        zm, zv, ll = np.zeros(n), np.ones(n), np.zeros(n)
        shift = effect_likelihood(*args, zm, zv, ll, work_arrays(n, 2), others)
        outs.append((shift, zm, zv, ll))
    assert outs[0][0] == outs[1][0]
    for k in (1, 2, 3):
        np.testing.assert_array_equal(outs[0][k], outs[1][k])
    assert not np.array_equal(outs[0][3], outs[2][3])


def test_the_seal_reads_each_particle_at_the_estimate_plus_its_offset() -> None:
    """A G3 datum into the seal filter with every offset at c: its log-likelihoods are the
    shared-value likelihood's at the spring estimate + c x its sd (no added variance), bit
    for bit; a sign or scale error in the offset fails."""
    env = _env()
    batch, a = env.batch, env.batch.a
    model, bank = batch.setup.filters, batch.bank
    row = model.persistence[1]
    n = a["x"].shape[2]
    a["aux"][0, 1, row] = 0.7
    work = work_arrays(n, len(batch.setup.learn_cols))
    moments = _moments(0, bank, model, work)
    c_hat, c_var = moments[0], moments[1]
    k, g3 = int(model.ground_aux[1]), float(a["last"][0, -1])
    z0 = (a["aux"][0, 1, k].copy(), a["aux"][0, 1, k + 1].copy())  # the beliefs before
    x, w = a["x"][0, 1].copy(), a["w"][0, 1].copy()
    handle = tuple(int(h) for h in a["h_filter"][0])
    _effect_update(0, 1, k, g3, 1.0, moments, model.ground_stack[1], model.ground_own[1],
                   model.ground_other[1], bank, a["status"], work, model, handle,
                   model.learn_part.size + 1)  # fmt: skip
    got = work[5].copy()
    ref_work, ll = work_arrays(n, len(batch.setup.learn_cols)), np.empty(n)
    spring = min(max(c_hat + np.sqrt(c_var) * 0.7, 0.0), 1.0)
    effect_likelihood(g3, 1.0, x, w, model.critical[1], model.ground_stack[1],
                      model.ground_own[1], model.ground_other[1], spring, model.noise_scale,
                      0.0, z0[0].copy(), z0[1].copy(), ll, ref_work, np.empty(0))  # fmt: skip
    np.testing.assert_array_equal(got, ll)
    for wrong in (c_hat - np.sqrt(c_var) * 0.7, c_hat + 3 * np.sqrt(c_var) * 0.7):
        ll_wrong = np.empty(n)
        effect_likelihood(g3, 1.0, x, w, model.critical[1], model.ground_stack[1],
                          model.ground_own[1], model.ground_other[1], min(max(wrong, 0.0), 1.0),
                          model.noise_scale, 0.0, z0[0].copy(), z0[1].copy(), ll_wrong,
                          ref_work, np.empty(0))  # fmt: skip
        assert not np.array_equal(got, ll_wrong)


def test_single_and_vector_env_agree_and_the_option_changes_the_episode() -> None:
    """With the spring's move, as documented; a seal set at slot 150, a spring pair at 400."""
    kw = {"episode_slots": 600, "n_particles": 50, "preflight": "every_flight",
          "rejuvenation": "resample_move"}  # fmt: skip
    single, vec = run_option_lockstep(
        {"seal_cross_persistence": RHO}, {}, kw, lambda t: {150: 3, 400: 2}.get(t, 0)
    )
    np.testing.assert_array_equal(single.batch.a["aux"][0], vec.unwrapped.batch.a["aux"][0])
    vec.close()


def test_refused_with_the_seals_move_and_out_of_range() -> None:
    with pytest.raises(ValueError, match="seal_cross_persistence"):
        Scenario(seal_cross_persistence=0.99, rejuvenation="resample_move_both")
    for bad in (-0.1, 1.0):
        with pytest.raises(ValueError, match="seal_cross_persistence"):
            Scenario(seal_cross_persistence=bad)


def test_a_new_seal_set_keeps_what_the_old_seals_said_about_the_spring_estimate() -> None:
    """The spring and its estimate stay when the seals are changed: the new seal particles'
    offsets are the old ones resampled by the old seal weights (systematic, one uniform of
    the filter stream), then the AR(1) over the seal filter's pending flights (the stream's
    next normals), not fresh draws."""
    env = _env()
    batch, a = env.batch, env.batch.a
    row = batch.setup.filters.persistence[1]
    learn_now(batch, 0)  # the flights' batch learnt first, as reset_filter does
    a["pending"][0, 1] = 7.0
    u, w = a["aux"][0, 1, row].copy(), a["w"][0, 1].copy()
    assert a["part_age"][0, 0] > 0 and np.ptp(w) > 0.0  # a resampling shows
    twin = _twin(batch.rngs[0]["filter"])
    reset_filter(batch, 0, "seal")
    resampled = u[systematic_resample(w, twin)]
    keep = RHO**7
    expected = keep * resampled + np.sqrt(1.0 - keep * keep) * twin.standard_normal(u.size)
    np.testing.assert_allclose(a["aux"][0, 1, row], expected, rtol=0, atol=1e-15)
    assert not np.allclose(resampled, u)


def test_a_new_spring_pair_draws_them_anew_and_new_seals_with_it_keep_those() -> None:
    """A spring pair fitted (here with the seals in the same event, as a double replacement
    does) draws every offset anew; seals fitted before the spring has flown leave them: the
    old seals' weights say nothing about the new spring's error."""
    env = _env()
    batch, a = env.batch, env.batch.a
    row = batch.setup.filters.persistence[1]
    before = a["aux"][0, 1, row].copy()
    replace_part(batch, 0, "spring", failed=False)
    fresh = a["aux"][0, 1, row].copy()
    assert not np.any(np.isin(fresh, before))
    replace_part(batch, 0, "seal", failed=False)
    np.testing.assert_array_equal(a["aux"][0, 1, row], fresh)
