"""Lives drawn from the reference posterior's own model: the calibration metric's own bias.

The belief study (:mod:`experiments.belief_calibration`) judges a RUL distribution at
*stages*, fractions of each part's true life: a short life is judged early, when every belief
is still near the prior, a long one late. A posterior calibrated at every fixed age need not
be calibrated at such truth-defined ages. This module measures by how much, where the
posterior is exact by construction: each life's static parameters (the spring's ``(a0,
theta)``, the seal's ``theta``) from the prior, its installation effects from ``N(0, 1)``,
its in-flight batches (I8 or I9, the mean of 10 flights) and tests (G1 or G3, one after each
batch, optional) from the surrogate's tables with the stated run noise and the other part's
severity fraction growing linearly, ``age /`` :data:`OTHER_LIFE_FLIGHTS`; then the
:class:`~experiments.reference_model.ReferencePosterior` on those data, and the PIT of the
true RUL at each stage.

``python -m experiments.reference_posterior --synthetic N`` is the command line
(docs/beliefs.md).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.interpolate import RegularGridInterpolator
from tqdm.auto import tqdm

from experiments.belief_calibration import STAGES
from experiments.belief_common import INTERVAL, wilson_share
from experiments.reference_model import (
    BATCH,
    DEFAULT_MIN_ESS,
    TEST,
    PartModel,
    ReferencePosterior,
    check_points,
)

#: flights of the other part's life in the synthetic lives (its fraction grows linearly)
OTHER_LIFE_FLIGHTS = 3000.0
#: flights per in-flight batch (``Scenario.flight_update_flights``)
BATCH_FLIGHTS = 10


def measurement_moments(
    model: PartModel,
    kind: int,
    x0_m: float,
    log_theta: float,
    ages: np.ndarray,
    other: np.ndarray,
) -> tuple[float, float, float]:
    """Mean over the runs at ``ages`` (flights) of ``mu`` and ``tau``, and the variance
    ``sum sigma^2 / m^2`` of the runs' mean, for a part of ``(x0_m, log_theta)`` and the
    other part at fractions ``other``: scipy's bilinear interpolation of the surrogate tables
    on the growth model's own path (an implementation independent of the reference's
    kernel)."""
    d0 = model.growth.damage(np.array([x0_m]))[0]
    depth = model.growth.inverse_damage(d0 + np.exp(log_theta) * np.asarray(ages, dtype=float))
    points = np.column_stack([np.clip(depth / model.critical_m, 0.0, 1.0), other])
    grids = (model.own_grid, model.other_grid)
    mu, tau, run = (RegularGridInterpolator(grids, model.stacks[kind][q])(points) for q in range(3))
    m = len(ages)
    return float(mu.mean()), float(tau.mean()), float((run**2).sum() / m**2)


def synthetic_stage_pits(
    model: PartModel,
    lives: int,
    rng: np.random.Generator,
    *,
    stages: Sequence[float] = STAGES,
    tests: bool = True,
    log2_points: int = 12,
    min_ess: float = DEFAULT_MIN_ESS,
    progress: bool = False,
) -> dict[float, np.ndarray]:
    """Per stage, the PIT of each synthetic life's true RUL in the reference posterior at
    the first batch boundary at or past ``stage x L`` (module docstring)."""
    if isinstance(lives, bool) or not isinstance(lives, int) or lives < 1:
        raise ValueError(f"lives = {lives!r} must be an integer >= 1")
    bad = [s for s in stages if not 0.0 < s < 1.0]
    if bad or not stages:
        raise ValueError(f"stages = {list(stages)!r} must be fractions of life in (0, 1)")
    check_points(log2_points, min_ess)
    pits: dict[float, list[float]] = {s: [] for s in sorted(stages)}
    for _ in tqdm(range(lives), desc="synthetic lives", disable=not progress):
        x0, log_theta = (float(v[0]) for v in model.prior_points(rng.random((1, model.dims))))
        life = float(model.lives(np.array([x0]), np.array([log_theta]))[1][0])
        z = rng.normal(size=2)  # the batch feature's and the test feature's effects
        ref = ReferencePosterior(model, rng, log2_points)
        age = 0
        for stage in pits:
            while age < stage * life:
                ages = np.arange(age, age + BATCH_FLIGHTS, dtype=np.float64)
                runs = [(BATCH, ages)] + ([(TEST, ages[-1:] + 1.0)] if tests else [])
                for kind, at in runs:
                    other = np.minimum(at / OTHER_LIFE_FLIGHTS, 1.0)
                    mu, tau, var = measurement_moments(model, kind, x0, log_theta, at, other)
                    ref.update(kind, mu + tau * z[kind] + np.sqrt(var) * rng.normal(), at, other)
                age += BATCH_FLIGHTS
            if age >= life:
                break  # the life ended inside the last batch: no later stage
            w = ref.weights(float(age))
            if 1.0 / (w @ w) < min_ess:
                ref.refine(float(age))
                w = ref.weights(float(age))
            pits[stage].append(float(w[ref.life <= life].sum()))
    return {s: np.asarray(p) for s, p in pits.items()}


def format_synthetic(pits: dict[float, np.ndarray], low_quantile: float = 0.05) -> str:
    """Undercut of the low quantile, share above the 95 % quantile and coverage of the 90 %
    interval per stage, each share with its Wilson 95 % interval (each life is judged once per
    stage, so its lives are independent); ``no lives`` for a stage no life reached."""
    width = 21
    lines = [
        f"{'stage':>5s} {'lives':>5s} "
        + " ".join(f"{h:>{width}s}" for h in ("undercut", "above", "coverage"))
    ]
    for s, p in pits.items():
        if p.size == 0:
            lines.append(f"{s:5.2f} {0:5d} no lives")
            continue
        cells = []
        for hits in (
            p < low_quantile,
            p > INTERVAL[1],
            (p >= INTERVAL[0]) & (p <= INTERVAL[1]),
        ):
            share, low, high, _ = wilson_share(hits)
            cells.append(f"{share:.3f} [{low:.3f}, {high:.3f}]")
        lines.append(f"{s:5.2f} {p.size:5d} " + " ".join(f"{c:>{width}s}" for c in cells))
    return "\n".join(lines)


__all__ = [
    "OTHER_LIFE_FLIGHTS",
    "format_synthetic",
    "measurement_moments",
    "synthetic_stage_pits",
]
