"""Integrator speed and accuracy: real-time factor, batch throughput, error vs fine step.

Usage: ``python scripts/bench_integrator.py [--dt 2.5e-4] [--friction-velocity 2e-3]``.
Without options the ScasParams defaults are used. See scas_env.studies.integrator_speed.
"""

from __future__ import annotations

import argparse

import numba

from scas_env.actuator.params import ScasParams
from scas_env.studies.integrator_speed import benchmark_integrator, format_results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dt", type=float, default=None, help="sim_dt_s override (s)")
    parser.add_argument(
        "--friction-velocity", type=float, default=None, help="friction_velocity_m_s override"
    )
    parser.add_argument("--duration", type=float, default=60.0, help="seconds per command")
    parser.add_argument("--batch-runs", type=int, default=8, help="runs in the batch timing")
    parser.add_argument("--substeps", type=int, default=10, help="RK4 substeps of the reference")
    args = parser.parse_args()
    params = ScasParams()
    if args.dt is not None:
        params = params.replace(sensors=params.sensors.replace(sim_dt_s=args.dt))
    if args.friction_velocity is not None:
        params = params.replace(
            actuator=params.actuator.replace(friction_velocity_m_s=args.friction_velocity)
        )
    print(
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


if __name__ == "__main__":
    main()
