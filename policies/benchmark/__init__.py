"""The policy benchmark: one episode runner, every policy on the same seeds, statistics and
reports. ``run_benchmark`` is the entry point (:mod:`policies.benchmark.run`)."""

from policies.benchmark.run import (
    DEFAULT_POLICIES,
    BenchmarkResult,
    PolicySpec,
    episode_seeds,
    run_benchmark,
)

__all__ = ["DEFAULT_POLICIES", "BenchmarkResult", "PolicySpec", "episode_seeds", "run_benchmark"]
