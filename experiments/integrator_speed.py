"""Speed and accuracy benchmark of the actuator integrator (docs/speed.md; part of ``make
bench``: ``python -m experiments.integrator_speed``).

For each benchmark command (pre-flight-test-like steps and a flight-like sine sum) it
measures, after JIT warm-up and as the best of ``repeats`` timings:

* the real-time factor of one actuator on one core, ``duration / wall time``, for the
  noise-free kernel run and for a full :func:`simulate` call with noise (noise drawing
  included);
* the batch throughput on all cores (:func:`experiments.physics_batch.simulate_batch`,
  simulated actuator-seconds per wall-clock second, noise on);
* the accuracy against a fine-step reference: the same kernel with ``reference_substeps``
  RK4 substeps per controller step (the digital controller keeps its rate, so only the
  integration error is measured), noise off, same command: max position error (m) and the
  relative error of the seal friction work.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from experiments.physics_batch import simulate_batch
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import ActuatorConfig, simulate

STEP_LEVELS_MM = (0.0, 1.0, 0.0, -1.0, 0.0, 2.0, 0.0, -2.0)  # pre-flight-like step cycle


def step_command(
    duration_s: float, sample_rate_hz: float, dwell_s: float = 0.5
) -> NDArray[np.float64]:
    """Pre-flight-test-like command (m): levels 0, +1, 0, -1, 0, +2, 0, -2 mm, ``dwell_s``
    each, repeated.

    >>> step_command(2.0, 4.0, dwell_s=0.5) * 1e3
    array([ 0.,  0.,  1.,  1.,  0.,  0., -1., -1.])
    """
    _check_positive(duration_s=duration_s, sample_rate_hz=sample_rate_hz, dwell_s=dwell_s)
    t = np.arange(round(duration_s * sample_rate_hz)) / sample_rate_hz
    idx = np.floor(t / dwell_s + 1e-9).astype(np.int64) % len(STEP_LEVELS_MM)
    return np.asarray(STEP_LEVELS_MM)[idx] * 1e-3


def sine_command(duration_s: float, sample_rate_hz: float) -> NDArray[np.float64]:
    """Flight-like command (m): 0.3 mm at 2 Hz + 2 mm at 0.8 Hz ([DJS20] Table 1 SCAS rows)."""
    _check_positive(duration_s=duration_s, sample_rate_hz=sample_rate_hz)
    t = np.arange(round(duration_s * sample_rate_hz)) / sample_rate_hz
    return 0.3e-3 * np.sin(2 * np.pi * 2.0 * t) + 2e-3 * np.sin(2 * np.pi * 0.8 * t)


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not value > 0.0:
            raise ValueError(f"{name} = {value} must be > 0")


@dataclass(frozen=True)
class BenchResult:
    """Figures of one benchmark command (see the module docstring)."""

    name: str
    duration_s: float
    dt_s: float
    rtf_kernel: float
    rtf_with_noise: float
    batch_runs: int
    batch_throughput: float
    max_position_error_m: float
    friction_work_rel_error: float


def _best_time(fn: Callable[[], object], repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return float(best)


def benchmark_integrator(
    params: ScasParams,
    *,
    duration_s: float = 60.0,
    reference_substeps: int = 10,
    batch_runs: int = 8,
    repeats: int = 3,
    seed: int = 0,
) -> list[BenchResult]:
    """Run the benchmark for the step and sine commands with ``params`` (its ``sim_dt_s``)."""
    if not (isinstance(reference_substeps, int) and reference_substeps >= 2):
        raise ValueError(f"reference_substeps = {reference_substeps} must be an int >= 2")
    if not (isinstance(batch_runs, int) and batch_runs >= 1):
        raise ValueError(f"batch_runs = {batch_runs} must be an int >= 1")
    if not (isinstance(repeats, int) and repeats >= 1):
        raise ValueError(f"repeats = {repeats} must be an int >= 1")
    config = ActuatorConfig.from_params(params)
    fine = dataclasses.replace(config, substeps=reference_substeps)
    fs = config.sample_rate_hz
    seeds = np.random.SeedSequence(seed).spawn(batch_runs + 1)
    warm = step_command(0.05, fs)
    simulate(config, warm, rng=np.random.default_rng(seeds[0]))
    simulate_batch([config] * 2, warm, rngs=seeds[:2])
    results = []
    for name, make in (("steps", step_command), ("sine", sine_command)):
        cmd = make(duration_s, fs)
        t_kernel = _best_time(lambda c=cmd: simulate(config, c, rng=None, noise=False), repeats)
        t_noise = _best_time(
            lambda c=cmd: simulate(config, c, rng=np.random.default_rng(seeds[0])), repeats
        )
        t_batch = _best_time(
            lambda c=cmd: simulate_batch([config] * batch_runs, c, rngs=seeds[1:]), repeats
        )
        run = simulate(config, cmd, rng=None, noise=False)
        ref = simulate(fine, cmd, rng=None, noise=False)
        results.append(
            BenchResult(
                name=name,
                duration_s=duration_s,
                dt_s=config.dt_s,
                rtf_kernel=duration_s / t_kernel,
                rtf_with_noise=duration_s / t_noise,
                batch_runs=batch_runs,
                batch_throughput=batch_runs * duration_s / t_batch,
                max_position_error_m=float(np.max(np.abs(run.position_m - ref.position_m))),
                friction_work_rel_error=abs(run.friction_work_j / ref.friction_work_j - 1.0),
            )
        )
    return results


def format_results(results: list[BenchResult]) -> str:
    """Plain-text table of :func:`benchmark_integrator` results."""
    lines = [
        f"{'command':8s} {'dt_s':>8s} {'RTF kernel':>11s} {'RTF +noise':>11s} "
        f"{'batch x/s':>10s} {'max|dx| um':>11s} {'dW/W':>9s}"
    ]
    for r in results:
        lines.append(
            f"{r.name:8s} {r.dt_s:8.1e} {r.rtf_kernel:11.0f} {r.rtf_with_noise:11.0f} "
            f"{r.batch_throughput:10.0f} {r.max_position_error_m * 1e6:11.4f} "
            f"{r.friction_work_rel_error:9.1e}"
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """The command line: the table of :func:`benchmark_integrator` for the design (``--params``,
    ``--dt``, ``--friction-velocity`` override it)."""
    import numba

    from experiments.cli_common import add_params_arg, load_params
    from scas_env.cli_args import (
        add_logging_args,
        configure_logging,
        make_parser,
        positive_float,
        positive_int,
    )

    parser = make_parser("python -m experiments.integrator_speed", __doc__)
    parser.add_argument(
        "--dt", type=positive_float, default=None, help="sim_dt_s override in s (default: params)"
    )
    parser.add_argument(
        "--friction-velocity",
        type=positive_float,
        default=None,
        help="friction_velocity_m_s override in m/s (default: params)",
    )
    parser.add_argument("--duration", type=positive_float, default=60.0, help="seconds per command")
    parser.add_argument(
        "--batch-runs", type=positive_int, default=8, help="runs in the batch timing"
    )
    parser.add_argument(
        "--substeps", type=int, default=10, help="RK4 substeps of the reference (>= 2)"
    )
    add_params_arg(parser)
    add_logging_args(parser)
    args = parser.parse_args(argv)
    configure_logging(args)
    params = load_params(parser, args)
    try:
        if args.dt is not None:
            params = params.replace(sensors=params.sensors.replace(sim_dt_s=args.dt))
        if args.friction_velocity is not None:
            params = params.replace(
                actuator=params.actuator.replace(friction_velocity_m_s=args.friction_velocity)
            )
        if args.substeps < 2:
            raise ValueError(f"--substeps {args.substeps} must be >= 2")
    except ValueError as exc:
        parser.error(str(exc))
    logging.getLogger(__name__).info(
        f"sim_dt_s = {params.sensors.sim_dt_s} s, friction_velocity_m_s = "
        f"{params.actuator.friction_velocity_m_s} m/s, {numba.get_num_threads()} threads, "
        f"{args.duration} s per command; reference = {args.substeps} RK4 substeps per step"
    )
    results = benchmark_integrator(
        params,
        duration_s=args.duration,
        reference_substeps=args.substeps,
        batch_runs=args.batch_runs,
    )
    print(format_results(results))
    print("RTF = simulated s / wall s (one actuator, one core); batch x/s = all cores")
    return 0


__all__ = [
    "BenchResult",
    "benchmark_integrator",
    "format_results",
    "main",
    "sine_command",
    "step_command",
]


if __name__ == "__main__":
    raise SystemExit(main())
