"""Flight-to-flight damage scatter: one scaled window, whole flights, and the closed form.

:func:`damage_scatter` measures the three estimates of docs/physics.md ("That window scatter
is not a flight's"): the calibration's scaled-window CV, the CV over whole simulated
flights (:func:`scas_env.actuator.calibration.whole_flight_scatter`, the calibration's
seeds) and the closed form of a flight as a sum of independent regime windows
(:func:`summed_cv`, each Table-1 regime simulated alone in ``n_windows`` windows of
``window_s``). The command line (docs/findings.md, "Environment"; about 8 min)::

    python -m experiments.damage_scatter --flights 40 --windows 60 --out results/damage_scatter.json
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from tqdm.auto import tqdm

from scas_env.actuator.calibration import calibration_for, whole_flight_scatter
from scas_env.actuator.flight_damage import simulated_flight_damage
from scas_env.actuator.missions import REGIMES
from scas_env.actuator.params import ScasParams

FloatArray = npt.NDArray[np.float64]

__all__ = ["damage_scatter", "main", "summed_cv"]


def summed_cv(means: npt.ArrayLike, variances: npt.ArrayLike, counts: npt.ArrayLike) -> FloatArray:
    """Coefficient of variation of a sum of independent blocks.

    Block type ``r`` (e.g. a window of one Table-1 regime) has mean ``means[r]`` and
    variance ``variances[r]`` and occurs ``counts[r]`` times; the sum has mean
    ``sum_r n_r m_r`` and variance ``sum_r n_r v_r``, so for one block type the CV falls as
    ``1 / sqrt(n)``. Axis 0 runs over block types; further axes (e.g. crack depths) are
    kept.

    >>> float(summed_cv([2.0], [1.0], [4.0])[()])
    0.25
    """
    m = np.asarray(means, dtype=np.float64)
    v = np.asarray(variances, dtype=np.float64)
    n = np.asarray(counts, dtype=np.float64)
    if m.shape != v.shape or m.shape[:1] != n.shape:
        raise ValueError(
            f"means {m.shape}, variances {v.shape} and counts {n.shape} must share axis 0"
        )
    if np.any(v < 0.0) or np.any(n < 0.0):
        raise ValueError("variances and counts must be >= 0")
    n = n.reshape(n.shape + (1,) * (m.ndim - 1))
    total = (n * m).sum(axis=0)
    if np.any(total <= 0.0):
        raise ValueError(f"the summed mean {total} must be > 0 to define a CV")
    return np.sqrt((n * v).sum(axis=0)) / total


def damage_scatter(
    params: ScasParams,
    *,
    n_flights: int,
    n_windows: int,
    window_s: float = 20.0,
    seed: int | None = None,
    progress: bool = True,
) -> dict[str, Any]:
    """The three CV estimates per crack depth and for wear, and the mean growth checks.

    ``seed`` defaults to the calibration's (the whole flights are then the shipped ones);
    regime r's windows draw from ``SeedSequence(seed, spawn_key=(3, r))``.
    """
    cal = calibration_for(params)
    seed = cal.seed if seed is None else seed
    depths = cal.crack_cv_depth_m
    whole = whole_flight_scatter(params, seed, n_flights, depths, progress=progress)
    regimes = []
    for r in tqdm(range(len(REGIMES)), desc="regime windows", disable=not progress):
        children = np.random.SeedSequence(seed, spawn_key=(3, r)).spawn(n_windows)
        rngs = [np.random.default_rng(c) for c in children]
        regimes.append(simulated_flight_damage(params, depths, rngs, duration_s=window_s, regime=r))
    counts = np.array([g.occurrence * cal.flight_duration_s / window_s for g in REGIMES])
    crack_m = np.array([d.crack_m.mean(axis=0) for d in regimes])
    crack_v = np.array([d.crack_m.var(axis=0, ddof=1) for d in regimes])
    wear_m = np.array([d.wear_m.mean() for d in regimes])
    wear_v = np.array([d.wear_m.var(ddof=1) for d in regimes])
    table = np.interp(depths, cal.crack_depth_m, cal.crack_rate_m_per_flight)
    return {
        "depth_m": depths.tolist(),
        "n_flights": n_flights,
        "n_windows_per_regime": n_windows,
        "window_cv": {"crack": cal.crack_cv.tolist(), "wear": cal.wear_cv},
        "whole_flight_cv": {"crack": whole.crack_cv.tolist(), "wear": whole.wear_cv},
        "closed_form_cv": {
            "crack": summed_cv(crack_m, crack_v, counts).tolist(),
            "wear": float(summed_cv(wear_m, wear_v, counts)),
        },
        "whole_flight_mean_over_table": {
            "crack": (whole.crack_m.mean(axis=0) / table).tolist(),
            "wear": float(whole.wear_m.mean() / cal.wear_rate_m_per_flight),
        },
    }


def main(argv: Sequence[str] | None = None) -> int:
    """The command line (module docstring): the estimates as JSON, printed and written."""
    from experiments.cli_common import add_params_arg, check_out_file, int_at_least, load_params
    from scas_env.cli_args import make_parser, nonneg_int
    from scas_env.utils.atomic_file import write_text_atomic
    from scas_env.utils.results_folder import json_text

    parser = make_parser("python -m experiments.damage_scatter", __doc__)
    parser.add_argument("--flights", type=int_at_least(2), default=40, help="whole flights")
    parser.add_argument("--windows", type=int_at_least(2), default=60, help="windows per regime")
    parser.add_argument(
        "--seed", type=nonneg_int, default=None, help="root seed (default: the calibration's)"
    )
    parser.add_argument("--out", type=Path, required=True, help="output JSON")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    add_params_arg(parser)
    args = parser.parse_args(argv)
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    result = damage_scatter(params, n_flights=args.flights, n_windows=args.windows, seed=args.seed)
    text = json_text(result, indent=1)
    write_text_atomic(args.out, text)
    print(text, end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
