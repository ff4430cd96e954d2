"""``Scenario(seal_reads_g1=1)``: the seal filter learns from the pre-flight test's G1 too, read
along its own wear at the spring's estimate, with a belief of G1's installation effect of its
own (docs/beliefs.md, cross-fault errors)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator
from scipy.stats import norm

from experiments.belief_calibration import policy_action
from scas_env.core import filters
from scas_env.core.filters import _effect_update, _moments, work_arrays
from scas_env.core.parts import learn_now, replace_part
from scas_env.core.rejuvenation import H_AUX, H_RUNS, H_TABLE, H_Y, SET_EFFECT
from scas_env.core.scenario import Scenario
from scas_env.env import ScasMaintenanceEnv
from tests.option_lockstep import run_option_lockstep
from tests.test_rejuvenation_seal import (
    _assert_the_replay_is_the_filters,
    _episode,
    _replay,
    _rows,
)

#: the configuration it is measured in (paper preset): the spring's move and factor 500, the
#: seal's spring error carried as offsets
MEASURED = {"preflight": "every_flight", "rejuvenation": "resample_move",
            "cross_variance_inflation": 500.0, "seal_cross_persistence": 0.9954}  # fmt: skip


def _env(slots: int = 60, **kw: object) -> ScasMaintenanceEnv:
    env = ScasMaintenanceEnv(seal_reads_g1=1, n_particles=200, **{**MEASURED, **kw})
    env.reset(seed=3)
    for t in range(slots):
        env.step(policy_action("test10", t))
    return env


def _ready(env: ScasMaintenanceEnv) -> tuple:
    """Row 0 with nothing pending (no batch, no prediction), so a test's updates start at the
    state as it is; returns (batch, a, model, handle, work)."""
    batch, a = env.batch, env.batch.a
    a["flight_count"][0] = 0
    a["flight_sum"][0] = 0.0
    a["pending"][0] = 0.0
    handle = tuple(int(h) for h in a["h_filter"][0])
    work = work_arrays(a["x"].shape[2], len(batch.setup.learn_cols))
    return batch, a, batch.setup.filters, handle, work


def _g1_into_seal(g1: float, moments: tuple, batch, model, handle: tuple, work: tuple) -> None:
    """G1 into row 0's seal filter as the kernel's test does it."""
    a = batch.a
    _effect_update(0, 1, int(model.ground_aux[2]), g1, 1.0, moments, model.ground_stack[2],
                   model.ground_own[2], model.ground_other[2], batch.bank, a["status"], work,
                   model, handle, model.learn_part.size + 2)  # fmt: skip


def test_a_g1_datum_into_the_seal_is_its_density_on_the_surrogates_tables() -> None:
    """Each seal particle's log-likelihood of G1 is the normal density of the surrogate's G1
    at (the spring's estimate, the particle's wear), interpolated by scipy on the tables as
    stored (crack on axis 1), with the particle's effect belief: mean mu + tau z, variance
    tau^2 v + run^2. The offsets at 0 put every particle at the estimate, no variance added.
    Read on the untransposed tables (wear taken for crack), it is not."""
    env = _env()
    batch, a, model, handle, work = _ready(env)
    row = int(model.ground_aux[2])
    a["aux"][0, 1, model.persistence[1]] = 0.0
    moments = _moments(0, batch.bank, model, work)
    z_mean, z_var = a["aux"][0, 1, row].copy(), a["aux"][0, 1, row + 1].copy()
    x = a["x"][0, 1].copy()
    g1 = float(a["last"][0, -2])
    _g1_into_seal(g1, moments, batch, model, handle, work)
    got = work[5].copy()

    sur = batch.setup.surrogate
    k = sur.index("G1")
    pts = np.column_stack([np.full(x.size, moments[0]), np.clip(x / model.critical[1], 0, 1)])
    mu, tau, run = (
        RegularGridInterpolator((sur.crack_grid, sur.wear_grid), t[k])(pts)
        for t in (sur.mean, sur.unit_std, sur.run_std)
    )
    run = run * model.noise_scale
    expected = norm.logpdf(g1, mu + tau * z_mean, np.sqrt(tau**2 * z_var + run**2))
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)

    swapped = RegularGridInterpolator((sur.crack_grid, sur.wear_grid), sur.mean[k])(pts[:, ::-1])
    assert not np.allclose(swapped, mu, rtol=1e-3), "the check cannot tell the axes apart"


def test_a_test_is_the_two_readings_then_g1_into_the_seal_at_the_same_moments() -> None:
    """The kernel's test with the option equals the test without it followed by G1's update of
    the seal at the moments both filters had before the test, bit for bit (particles,
    weights, effect beliefs, offsets, the stream). G1 read at the moments after the spring
    learnt it is not the same."""
    outs = []
    for manual in (False, True, "after"):
        env = _env()
        batch, a, model, handle, work = _ready(env)
        g1, g3 = float(a["last"][0, -2]), float(a["last"][0, -1])
        off = model._replace(ground_aux=np.array([*model.ground_aux[:2], -1]))
        moments = _moments(0, batch.bank, model, work)
        args = (a["pending"], a["flight_sum"], a["flight_count"], a["batch_usage"], a["status"],
                work, model if not manual else off, handle)  # fmt: skip
        filters.test_row(0, g1, g3, batch.bank, *args)
        if manual:
            if manual == "after":
                moments = _moments(0, batch.bank, model, work)
            _g1_into_seal(g1, moments, batch, model, handle, work)
        assert a["status"][0] == 0
        stream = batch.rngs[0]["filter"].random(4)  # where the filter stream stands
        outs.append([arr[0].copy() for arr in batch.bank[:5]] + [stream])
    for got, want in zip(outs[0], outs[1], strict=True):
        np.testing.assert_array_equal(got, want)
    assert not all(np.array_equal(g, w) for g, w in zip(outs[0], outs[2], strict=True))


def test_g1s_effect_is_kept_with_new_seals_and_reset_with_a_new_spring_pair() -> None:
    """G1's effect belongs to the installation, as G3's does: new seals keep the old seal
    filter's belief of it collapsed to one Gaussian (the weighted mixture's mean and
    variance); a new spring pair is a new installation (N(0, 1))."""
    env = _env()
    a = env.batch.a
    row = int(env.batch.setup.filters.ground_aux[2])
    replace_part(env.batch, 0, "seal", failed=False)  # learns the pending batch first
    twin = _env()  # the same episode: its seal filter as replace_part finds it
    learn_now(twin.batch, 0)
    w = twin.batch.a["w"][0, 1]
    m, v = twin.batch.a["aux"][0, 1, row], twin.batch.a["aux"][0, 1, row + 1]
    mean = np.sum(w * m)
    var = np.sum(w * (v + (m - mean) ** 2))
    assert np.ptp(m) > 0.0, "one belief for all particles: the mixture is not checked"
    np.testing.assert_allclose(a["aux"][0, 1, row], mean, rtol=1e-12)
    np.testing.assert_allclose(a["aux"][0, 1, row + 1], var, rtol=1e-12)
    replace_part(env.batch, 0, "spring", failed=False)
    np.testing.assert_array_equal(a["aux"][0, 1, row], 0.0)
    np.testing.assert_array_equal(a["aux"][0, 1, row + 1], 1.0)


@pytest.mark.parametrize(
    "config", [MEASURED, {"preflight": "every_flight", "rejuvenation": "resample_move_both"}]
)
def test_single_and_vector_env_agree_and_the_option_changes_the_episode(config: dict) -> None:
    """With the seal's offsets or with its move; a seal set at slot 150, a spring pair at
    400."""
    kw = {**config, "episode_slots": 600, "n_particles": 50}
    single, vec = run_option_lockstep(
        {"seal_reads_g1": 1}, {}, kw, lambda t: {150: 3, 400: 2}.get(t, 0)
    )
    np.testing.assert_array_equal(single.batch.a["aux"][0], vec.unwrapped.batch.a["aux"][0])
    vec.close()


def test_with_the_seals_move_its_history_keeps_g1_and_replays_the_filter() -> None:
    """With ``rejuvenation="resample_move_both"`` the seal's history holds G1 data (table: the
    learning features' count + 2) and a belief row of G1's effect at the seal's fitting and
    at the spring pair's (N(0, 1)); every seal particle's log-likelihood and effect beliefs
    are its history's replay (moves made). Without G1's data in the replay they are not."""
    env = _episode(200, seal_reads_g1=1)
    rows = _rows(env)
    n_learn = env.setup.filters.learn_part.size
    data = rows[rows[:, H_TABLE] != SET_EFFECT]
    assert set(data[:, H_TABLE]) == {1.0, float(n_learn + 1), float(n_learn + 2)}
    belief = rows[rows[:, H_TABLE] == SET_EFFECT]
    np.testing.assert_array_equal(np.sort(belief[:3, H_AUX]), [0.0, 2.0, 4.0])
    np.testing.assert_array_equal(belief[3:, [H_Y, H_RUNS]], [[0.0, 1.0]] * 3)
    lam = _assert_the_replay_is_the_filters(env)
    a = env.batch.a
    history, n = a["history"], a["history_n"]
    kept = rows[rows[:, H_TABLE] != n_learn + 2]
    history[0, 1, : kept.shape[0]] = kept
    n[0, 1] = kept.shape[0]
    wrong, _ = _replay(env, lam)
    assert np.max(np.abs(wrong - a["loglik"][0, 1])) > 0.1


def test_out_of_range_is_refused() -> None:
    for bad in (-1, 2, 0.5):
        with pytest.raises(ValueError, match="seal_reads_g1"):
            Scenario(seal_reads_g1=bad)
