"""What the pre-flight test's go/no-go does to actuators of known health, in both meanings.

For each go/no-go meaning (``"detection_band"``: v0; ``"airworthiness"``: v1, see
:mod:`scas_env.core.acceptance`) and each part at fractions of its critical level (the other
part new), ``n_units`` installations of the surrogate world are drawn, each with its own
installation effects and recorded reference, and tested once: the share of failed tests
with its Wilson 95 % interval (scipy), beside the normal-theory probability of the
airworthiness limit. The issue's targets (a healthy unit fails <= 1e-3 of tests, a part at
its critical level >= 0.9) are printed beside each figure by ``scripts/go_no_go.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import binomtest

from scas_env.core.acceptance import AirworthinessLimits
from scas_env.env import ScasMaintenanceEnv

MODES = ("detection_band", "airworthiness")
SEVERITIES = (0.0, 0.25, 0.5, 0.75, 0.9, 1.0)
#: targets of the sensing issue: (healthy at most, a part at critical at least)
TARGETS = {"healthy_max": 1e-3, "critical_min": 0.9}


def no_go_rates(
    n_units: int = 2000,
    severities: tuple[float, ...] = SEVERITIES,
    seed: int = 0,
) -> list[dict[str, float | str]]:
    """Rows (mode, part, severity, failed tests, share, Wilson interval, model probability)."""
    if isinstance(n_units, bool) or not isinstance(n_units, int) or n_units < 1:
        raise ValueError(f"n_units = {n_units!r} must be an integer >= 1")
    bad = [s for s in severities if not 0.0 <= s <= 1.0]
    if bad:
        raise ValueError(f"severities {bad} must lie in [0, 1] (fractions of critical)")
    rows: list[dict[str, float | str]] = []
    for m, mode in enumerate(MODES):
        env = ScasMaintenanceEnv(go_no_go=mode)
        world, limits = env.world, env.limits
        for p, part in enumerate(("spring", "seal")):
            for s, severity in enumerate(severities):
                rng = np.random.default_rng((seed, m, p, s))
                fails = sum(
                    _one_test(env, world, limits, rng, part, severity) for _ in range(n_units)
                )
                ci = binomtest(fails, n_units).proportion_ci(0.95, method="wilson")
                model = np.nan
                if limits is not None:
                    c, w = (severity, 0.0) if part == "spring" else (0.0, severity)
                    model = limits.no_go_probability(c, w)
                rows.append(
                    {
                        "go_no_go": mode,
                        "part": part,
                        "severity": severity,
                        "tests": n_units,
                        "no_go": fails,
                        "share": fails / n_units,
                        "ci_low": float(ci.low),
                        "ci_high": float(ci.high),
                        "model": float(model),
                    }
                )
    return rows


def _one_test(
    env: ScasMaintenanceEnv,
    world: object,
    limits: AirworthinessLimits | None,
    rng: np.random.Generator,
    part: str,
    severity: float,
) -> bool:
    """A new installation, its reference recorded, one test at ``severity`` of ``part``."""
    world.reset(rng)  # type: ignore[attr-defined]
    reference = (
        world.installation_reference(rng, limits.reference_tests)  # type: ignore[attr-defined]
        if limits is not None
        else {}
    )
    if part == "spring":
        world.crack_m, world.wear_m = severity * world.spring_failure_m, 0.0  # type: ignore[attr-defined]
    else:
        world.crack_m = 0.0  # type: ignore[attr-defined]
        world.wear_m = severity * env.calibration.seal_critical_wear_m  # type: ignore[attr-defined]
    feats = world.test(rng)  # type: ignore[attr-defined]
    if limits is not None:
        return not limits.passes(feats, reference)
    return not env.builder.within_acceptance(feats)


def format_rates(rows: list[dict[str, float | str]]) -> str:
    """A text table with each healthy and critical figure beside its target."""
    lines = [
        f"{'go/no-go':15s} {'part':6s} {'severity':>8s} {'no-go share':>11s} "
        f"{'95% CI':>19s} {'model':>8s}  target"
    ]
    for r in rows:
        target = ""
        if r["severity"] == 0.0:
            hi = TARGETS["healthy_max"]
            verdict = (
                "met"
                if float(r["ci_high"]) <= hi
                else "within CI"
                if float(r["ci_low"]) <= hi
                else "not met"
            )
            target = f"<= {hi:g} ({verdict})"
        elif r["severity"] == 1.0:
            lo = TARGETS["critical_min"]
            verdict = (
                "met"
                if float(r["share"]) >= lo
                else "within CI"
                if float(r["ci_high"]) >= lo
                else "not met"
            )
            target = f">= {lo:g} ({verdict})"
        lines.append(
            f"{r['go_no_go']:15s} {r['part']:6s} {float(r['severity']):8.2f} "
            f"{float(r['share']):11.4f} [{float(r['ci_low']):.4f}, {float(r['ci_high']):.4f}] "
            f"{float(r['model']):8.4f}  {target}"
        )
    return "\n".join(lines)


__all__ = ["MODES", "SEVERITIES", "TARGETS", "format_rates", "no_go_rates"]
