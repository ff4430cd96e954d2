"""Health dashboard: frame shape and type, same record -> same pixels, the crack bar's length
in pixels against the axis transform, the record against the env's own observation."""

from __future__ import annotations

import copy
import pickle

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from prognostics.rul import weighted_quantile
from scas_env.dashboard import (
    COLORS,
    DPI,
    FIGSIZE_IN,
    DashboardRenderer,
    HealthDashboard,
    HealthRecord,
    HealthTrace,
    PartRul,
    frame_record_from_env,
)

pytest.importorskip("matplotlib")
SHAPE = (round(FIGSIZE_IN[1] * DPI), round(FIGSIZE_IN[0] * DPI), 3)


def _record(crack_m: float = 3e-4, **changes) -> HealthRecord:
    rng = np.random.default_rng(0)
    rul = {
        p: PartRul(rng.gamma(9.0, 60.0, 200), np.full(200, 1 / 200), true_flights=t)
        for p, t in (("spring", 480.0), ("seal", 700.0))
    }
    fields = {
        "slots": np.arange(0, 51),
        "crack_fraction": np.linspace(0.1, crack_m / 1e-3, 51),
        "wear_fraction": np.linspace(0.0, 0.4, 51),
        "crack_depth_m": crack_m,
        "seal_wear_m": 4e-6,
        "spring_critical_m": 1e-3,
        "seal_critical_m": 1e-5,
        "rul": rul,
        "features": (("I2", 0.8, "-"), ("G1", 3.1, "uA")),
        "cost_usd": 1200.0,
        "revenue_usd": 1e5,
        "availability": 0.98,
        "flights": 49,
        "tests": 5,
    }
    fields.update(changes)
    return HealthRecord(**fields)


@pytest.fixture(scope="module")
def dashboard() -> HealthDashboard:
    return HealthDashboard()


def test_frame_shape_and_type(dashboard: HealthDashboard) -> None:
    frame = dashboard.draw(_record())
    assert frame.shape == SHAPE and frame.dtype == np.uint8
    assert frame.flags.writeable and frame.base is None  # a copy, not the canvas buffer


def test_same_record_same_pixels(dashboard: HealthDashboard) -> None:
    """Also across a cached background and a fresh figure."""
    first = dashboard.draw(_record())
    other = dashboard.draw(_record(crack_m=8e-4, slots=np.arange(1000, 1051)))
    assert not np.array_equal(first, other)
    np.testing.assert_array_equal(dashboard.draw(_record()), first)
    np.testing.assert_array_equal(HealthDashboard().draw(_record()), first)


def _bar_end_px(dashboard: HealthDashboard, frame: np.ndarray) -> int:
    """Rightmost pixel column of the crack bar's colour on the bar's middle row."""
    ax = dashboard.ax_gauges
    _, y = ax.transData.transform((0.0, 1.0))
    row = frame.shape[0] - round(float(y))
    rgb = np.array([int(COLORS["spring"][k : k + 2], 16) for k in (1, 3, 5)])
    hits = np.flatnonzero(np.all(np.abs(frame[row].astype(int) - rgb) <= 2, axis=1))
    assert hits.size, "crack bar not found"
    return int(hits.max())


@pytest.mark.parametrize("fraction", [0.2, 0.55, 0.9])
def test_crack_bar_moves_with_the_crack(dashboard: HealthDashboard, fraction: float) -> None:
    """The bar ends where the gauge axis puts crack / critical (within 2 px)."""
    frame = dashboard.draw(_record(crack_m=fraction * 1e-3))
    expected, _ = dashboard.ax_gauges.transData.transform((fraction, 1.0))
    assert abs(_bar_end_px(dashboard, frame) - expected) <= 2.0


def test_part_rul_quantiles_match_prognostics() -> None:
    rng = np.random.default_rng(3)
    samples, weights = rng.gamma(4.0, 100.0, 300), rng.random(300)
    d = PartRul(samples, weights / weights.sum(), true_flights=300.0)
    levels = (0.05, 0.5, 0.95)
    np.testing.assert_array_equal(
        d.quantiles(levels), weighted_quantile(samples, weights / weights.sum(), np.array(levels))
    )


def test_record_from_env_matches_the_observation() -> None:
    """The RUL distributions read from the filters give the env's own RUL observation."""
    env = gym.make(scas_env.ENV_ID)
    obs, info = env.reset(seed=5)
    trace = HealthTrace()
    trace.record(env)
    for k in range(60):
        obs, _, _, _, info = env.step(1 if k % 10 == 0 else 0)
        trace.record(env)
    names = env.unwrapped.obs_names
    record = frame_record_from_env(env, trace)
    assert record.crack_depth_m == info["true_state"]["crack_depth_m"]
    np.testing.assert_array_equal(record.slots, np.arange(61))
    assert record.crack_fraction[-1] == info["true_state"]["crack_fraction"]
    assert record.availability == info["availability"] and record.tests == info["tests"]
    for part in ("spring", "seal"):
        d = record.rul[part]
        low = env.unwrapped.scenario.rul_quantile
        assert d.mean == pytest.approx(float(obs[names.index(f"{part}_rul_mean")]), rel=1e-6)
        assert d.quantiles((low,))[0] == pytest.approx(
            float(obs[names.index(f"{part}_rul_low")]), rel=1e-6
        )
        assert d.true_flights == info["true_state"][f"{part}_rul_flights"]
    assert HealthDashboard().draw(record).shape == SHAPE


def test_renderer_without_filter_and_new_episode() -> None:
    env = gym.make(scas_env.ENV_ID, obs_mode="features")
    renderer = DashboardRenderer("rgb_array")
    env.reset(seed=0)
    renderer.observe(env)
    for _ in range(5):
        env.step(0)
        renderer.observe(env)
    assert frame_record_from_env(env, renderer.trace).rul is None
    assert renderer.render(env).shape == SHAPE
    frame = renderer.render(env)
    clone = pickle.loads(pickle.dumps(renderer))  # the figure is dropped and rebuilt
    np.testing.assert_array_equal(clone.render(env), frame)
    assert copy.deepcopy(renderer).trace.slots == renderer.trace.slots
    env.reset(seed=1)
    renderer.observe(env)
    assert renderer.trace.slots == [0]
    renderer.close()
    with pytest.raises(ValueError, match="render_mode"):
        DashboardRenderer("ansi")


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"wear_fraction": np.zeros(3)}, "equal"),
        ({"crack_fraction": np.full(51, np.nan)}, "finite"),
        ({"seal_critical_m": 0.0}, "seal_critical_m"),
        ({"availability": 1.5}, "availability"),
        ({"rul": {"spring": None}}, "keys"),
    ],
)
def test_bad_records_raise(changes: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        _record(**changes)


def test_bad_part_rul_raises() -> None:
    with pytest.raises(ValueError, match="summing to 1"):
        PartRul(np.ones(3), np.ones(3), true_flights=1.0)
    with pytest.raises(ValueError, match="true_flights"):
        PartRul(np.ones(2), np.full(2, 0.5), true_flights=float("nan"))


def test_benchmark_function_runs() -> None:
    """The frame benchmark (timings are reported by python -m experiments.dashboard_speed, not
    tested)."""
    from experiments.dashboard_speed import benchmark_frame_ms

    env = gym.make(scas_env.ENV_ID)
    env.reset(seed=0)
    assert set(benchmark_frame_ms(env, frames=3)) == {"median", "mean", "max", "cpu_median"}


def test_env_renders_the_dashboard_frame_by_frame() -> None:
    """``render_mode="rgb_array"``: the env's frame is the dashboard of its own record, the
    same pixels for the same seed and actions, another frame after more flights."""
    frames = []
    for _ in range(2):
        env = gym.make(scas_env.ENV_ID, render_mode="rgb_array", episode_slots=30)
        env.reset(seed=3)
        for k in range(12):
            env.step(1 if k % 4 == 0 else 0)
        frames.append(env.render())
        env.close()
    assert frames[0].shape == SHAPE and frames[0].dtype == np.uint8
    np.testing.assert_array_equal(frames[0], frames[1])
    env = gym.make(scas_env.ENV_ID, render_mode="rgb_array", episode_slots=30)
    env.reset(seed=3)
    env.step(0)
    assert not np.array_equal(env.render(), frames[0])


def test_human_mode_draws_in_reset_and_every_step(monkeypatch: pytest.MonkeyPatch) -> None:
    """Gymnasium's contract: ``render_mode="human"`` renders inside ``reset`` and ``step``
    (without a call to ``render``); the other modes draw only when asked."""
    drawn: list[int] = []
    monkeypatch.setattr(DashboardRenderer, "render", lambda self, env: drawn.append(env.slot))
    env = gym.make(scas_env.ENV_ID, render_mode="human")
    env.reset(seed=0)
    for _ in range(3):
        env.step(0)
    assert drawn == [0, 1, 2, 3]
    env = gym.make(scas_env.ENV_ID, render_mode="rgb_array")
    env.reset(seed=0)
    env.step(0)
    assert drawn == [0, 1, 2, 3]
