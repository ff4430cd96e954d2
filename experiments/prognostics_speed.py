"""Timing of the particle-filter hot path and the RUL summary beside the step-by-step reference
(``python -m experiments.prognostics_speed``, part of ``make bench``; docs/speed.md).

Synthetic Paris-like case (no simulator needed): ``g(a) = g_0 (a / a_0)^{m/2}`` tabulated on
200 depths, a PCHIP measurement model on 8 levels, N particles. Each timing is the median
over ``n_calls`` calls after ``n_warmup`` warm-up calls (numba compilation excluded); the
filter operations start each call from the same fresh cloud, reset outside the timed
region. "with resampling" uses a filter with ``resample_threshold = 1`` so that every
update resamples and regularises; "exact scheme" predicts with ``scheme="exact"`` (the
environment's crack filter). The reference is
:meth:`TabulatedRateModel.simulate_steps_to_threshold` (numpy, one loop iteration per step)
from the same cloud, about ``steps_to_threshold`` steps from failure.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence

import numpy as np

from prognostics.degradation_models import TabulatedRateModel, paris_crack_model
from prognostics.measurement import MeasurementModel
from prognostics.particle_filter import ParticleFilter
from prognostics.rul import HazardZone, RulPredictor, rul_summary


def _median_time_us(
    fn: Callable[[], object],
    n_calls: int,
    n_warmup: int,
    setup: Callable[[], object] | None = None,
) -> float:
    """Median of ``fn``'s wall time over ``n_calls`` calls, ``setup`` run untimed before each."""
    for _ in range(n_warmup):
        if setup is not None:
            setup()
        fn()
    samples = np.empty(n_calls)
    for k in range(n_calls):
        if setup is not None:
            setup()
        t0 = time.perf_counter()
        fn()
        samples[k] = time.perf_counter() - t0
    return float(np.median(samples) * 1e6)


def synthetic_case(
    steps_to_threshold: float = 2000.0,
) -> tuple[TabulatedRateModel, MeasurementModel, HazardZone, float]:
    """Paris-like model, measurement model, threshold, start depth ``steps`` from failure."""
    depth = np.linspace(1.0e-4, 1.0e-3, 200)  # m
    rate = 1.0e-7 * (depth / 1.0e-4) ** 1.125  # m/flight, m = 2.25
    model = paris_crack_model(depth, rate, process_noise_std_m=1e-7, log_theta_noise_std=0.005)
    levels = np.linspace(0.0, 1.0e-3, 8)
    meas = MeasurementModel(
        "pchip",
        sigma_knots=levels,
        sigma_values=np.linspace(0.02, 0.04, 8),
        knots=levels,
        values=(levels / 1.0e-3) ** 1.3,
        slopes=1.3e3 * (levels / 1.0e-3) ** 0.3,
    )
    threshold = 1.0e-3
    start = float(model.inverse_damage(model.damage(np.array([threshold])) - steps_to_threshold)[0])
    return model, meas, HazardZone(threshold), start


def run_benchmark(
    n_particles: int = 1000, n_calls: int = 2000, n_warmup: int = 200, seed: int = 0
) -> dict[str, float]:
    """Median time per call in microseconds for each operation (see module docstring)."""
    model, meas, hazard, start = synthetic_case()
    exact_model = dataclasses.replace(model, scheme="exact")
    rng = np.random.default_rng(seed)
    pf = ParticleFilter(model, meas, n_particles, rng)
    pf_always = ParticleFilter(model, meas, n_particles, rng, resample_threshold=1.0)
    pf_exact = ParticleFilter(exact_model, meas, n_particles, rng)
    x0 = start * (1.0 + 0.02 * rng.standard_normal(n_particles))
    th0 = rng.lognormal(0.0, 0.2, n_particles)
    y_flat = float(meas.mean(np.array([start]))[0])

    def fresh() -> None:
        pf.reset(x0, th0)
        pf_always.reset(x0, th0)
        pf_exact.reset(x0, th0)

    def timed(op: Callable[[], object]) -> float:
        return _median_time_us(op, n_calls, n_warmup, setup=fresh)

    out = {
        "predict": timed(lambda: pf.predict(1.0)),
        "measurement update (no resampling)": timed(lambda: pf.update(y_flat)),
        "step (no resampling)": timed(lambda: pf.step(1.0, y_flat)),
        "step (no resampling, exact scheme)": timed(lambda: pf_exact.step(1.0, y_flat)),
        "step (with resampling)": timed(lambda: pf_always.step(1.0, y_flat)),
    }
    out["estimate"] = _median_time_us(pf.estimate, n_calls, n_warmup)
    fresh()
    out["rul_summary (tabulated)"] = _median_time_us(
        lambda: rul_summary(pf.x, pf.theta, pf.weights, model, hazard, horizon_steps=100.0),
        n_calls,
        n_warmup,
    )
    fast = RulPredictor(model, hazard.mean, n_particles, horizon_steps=100.0)
    out["RulPredictor.summary (hot path)"] = _median_time_us(
        lambda: fast.summary(pf.x, pf.log_theta, pf.weights), n_calls, n_warmup
    )
    out["rul step-by-step (reference)"] = _median_time_us(
        lambda: model.simulate_steps_to_threshold(pf.x, pf.theta, hazard.mean, 1.0),
        5,
        1,
    )
    return out


def format_table(times_us: dict[str, float], n_particles: int) -> str:
    """Two-column Markdown table of the timings."""
    lines = [f"| operation (N = {n_particles}) | median us/call |", "|---|---:|"]
    lines += [f"| {k} | {v:.1f} |" for k, v in times_us.items()]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line: the Markdown table of :func:`run_benchmark`."""
    from scas_env.cli_args import make_parser, nonneg_int, positive_int

    parser = make_parser("python -m experiments.prognostics_speed", __doc__)
    parser.add_argument("--particles", type=positive_int, default=1000, help="particles N")
    parser.add_argument("--calls", type=positive_int, default=2000, help="timed calls")
    parser.add_argument("--seed", type=nonneg_int, default=0, help="seed")
    args = parser.parse_args(argv)
    times = run_benchmark(n_particles=args.particles, n_calls=args.calls, seed=args.seed)
    print(format_table(times, args.particles))
    return 0


__all__ = ["format_table", "main", "run_benchmark", "synthetic_case"]


if __name__ == "__main__":
    raise SystemExit(main())
