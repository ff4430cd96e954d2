"""The paper's physics figures (Figs. 3, 4, 5, 7a, 7b) and the demo's signals, drawn as PNG.

    python -m experiments.paper.figures --out results/figures

Object API only (``matplotlib.figure.Figure`` on an Agg canvas): no pyplot state, safe in
headless runs and threads. Each ``plot_*`` function takes the data of
:mod:`experiments.paper.figure_data` (or simulated runs) and an output path, writes a PNG at
:data:`DPI` (creating the parent folder) and returns the Figure.
"""

from __future__ import annotations

import argparse
import logging
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from experiments.paper.figure_data import (
    CrackGrowthCurves,
    FrequencyResponseCurves,
    NullBiasCurves,
    PaperFigures,
    SealGainCurves,
    SpringRateCurves,
    paper_figures,
)
from scas_env.actuator.physics.actuator import ActuatorRun
from scas_env.cli_args import keeps_results
from scas_env.utils.results_folder import json_text, results_folder

DPI = 120
MM = 1e3  # m -> mm
UM = 1e6  # m -> um
MA = 1e3  # A -> mA
UA = 1e6  # A -> uA


def _new_figure(nrows: int, ncols: int, size: tuple[float, float], title: str) -> Figure:
    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    fig.subplots(nrows, ncols, squeeze=False)
    fig.suptitle(title)
    return fig


def _save(fig: Figure, path: str | os.PathLike[str]) -> Figure:
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=DPI)
    return fig


def _colors(n: int) -> np.ndarray:
    """n colours of the viridis map, dark (healthy) to light (most severe)."""
    return colormaps["viridis"](np.linspace(0.0, 0.85, n))


def plot_fig3_spring_rate(data: SpringRateCurves, path: str | os.PathLike[str]) -> Figure:
    """Fig. 3: spring rate (eq. 1) and cracked-coil rate (eq. 5) against crack depth."""
    fig = _new_figure(1, 2, (10.0, 4.0), "Paper Fig. 3: centering-spring stiffness vs crack depth")
    ax_k, ax_c = fig.axes
    a = data.depth_m * MM
    ax_k.plot(a, data.spring_rate_exact_n_m / MM, label="exact J(a)")
    ax_k.plot(a, data.spring_rate_paper_n_m / MM, "--", label="printed eq. 6 J(a)")
    ax_k.axhline(data.healthy_rate_n_m / MM, color="grey", lw=0.8, label="healthy G d^4/(8 D^3 n)")
    ax_k.set(xlabel="crack depth a (mm)", ylabel="spring rate K (N/mm)", title="whole spring")
    ax_c.plot(a, data.coil_rate_exact_n_m / MM, label="exact J(a)")
    ax_c.plot(a, data.coil_rate_paper_n_m / MM, "--", label="printed eq. 6 J(a)")
    ax_c.set(xlabel="crack depth a (mm)", ylabel="coil rate K_f (N/mm)", title="cracked coil")
    for ax in (ax_k, ax_c):
        ax.axvline(
            data.failure_depth_m * MM,
            color="red",
            ls=":",
            label=f"failure depth ({data.governing.replace('_', ' ')})",
        )
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return _save(fig, path)


def plot_fig4_crack_growth(data: CrackGrowthCurves, path: str | os.PathLike[str]) -> Figure:
    """Fig. 4: crack depth against flights for several growth multipliers, and g(a)."""
    fig = _new_figure(1, 2, (11.0, 4.2), "Paper Fig. 4: spring-crack growth across flights")
    ax_a, ax_g = fig.axes
    for color, theta, n, a, n_f in zip(
        _colors(data.multipliers.size),
        data.multipliers,
        data.flights,
        data.depth_m,
        data.flights_to_failure,
        strict=True,
    ):
        ax_a.plot(n, a * MM, color=color, label=f"C x {theta:g}: {n_f:.0f} flights")
    ax_a.axhline(data.failure_depth_m * MM, color="red", ls=":", label="failure depth")
    ax_a.set(
        xlabel="flights",
        ylabel="crack depth a (mm)",
        title=f"from a0 = {data.initial_depth_m * UM:.0f} um",
    )
    ax_g.semilogy(data.table_depth_m * MM, data.table_rate_m_per_flight * UM, color="k")
    ax_g.axvline(data.failure_depth_m * MM, color="red", ls=":", label="failure depth")
    ax_g.axvline(
        data.dormant_below_m * MM, color="grey", ls="--", label="dormant below (threshold)"
    )
    ax_g.axvline(data.initial_depth_m * MM, color="tab:blue", ls="-.", label="initial flaw a0")
    ax_g.set(
        xlabel="crack depth a (mm)",
        ylabel="growth rate da/dflight (um/flight)",
        title="per-flight growth rate at nominal Paris C",
    )
    for ax in (ax_a, ax_g):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return _save(fig, path)


def plot_fig5_frequency_response(
    data: FrequencyResponseCurves, path: str | os.PathLike[str]
) -> Figure:
    """Fig. 5: closed-loop responses at several wear levels, cut-off vs K_i1 and vs wear."""
    fig = _new_figure(2, 2, (11.0, 8.0), "Paper Fig. 5: SCAS frequency response vs seal leakage")
    ax_m, ax_p, ax_k, ax_w = fig.axes
    for color, wear, mag, phase in zip(
        _colors(data.wear_m.size), data.wear_m, data.magnitude_db, data.phase_deg, strict=True
    ):
        label = f"wear {wear * UM:.1f} um ({wear / data.critical_wear_m:.1f} x critical)"
        ax_m.semilogx(data.freq_hz, mag, "o-", ms=3, color=color, label=label)
        ax_p.semilogx(data.freq_hz, phase, "o-", ms=3, color=color, label=label)
    ax_m.axhline(-3.0, color="grey", ls="--", lw=0.8, label="-3 dB")
    ax_m.set(xlabel="frequency (Hz)", ylabel="|X/X_cmd| (dB)", title="magnitude")
    ax_p.set(xlabel="frequency (Hz)", ylabel="phase (deg)", title="phase")
    ax_k.semilogx(data.sweep_k_i1_m3_s_pa, data.sweep_cutoff_hz, "o-", color="k", ms=3)
    ax_k.plot(
        data.critical_k_i1_m3_s_pa,
        data.critical_cutoff_hz,
        "r*",
        ms=12,
        label=f"critical: K_i1 = {data.critical_k_i1_m3_s_pa:.2e}",
    )
    ax_k.set(
        xlabel="leakage coefficient K_i1 (m^3/(s Pa))",
        ylabel="cut-off frequency (Hz)",
        title="cut-off vs laminar leakage (K_i2 > 0 past the lip wear)",
    )
    ax_w.plot(data.sweep_wear_m * UM, data.sweep_cutoff_hz, "o-", color="k", ms=3)
    ax_w.plot(
        data.critical_wear_m * UM,
        data.critical_cutoff_hz,
        "r*",
        ms=12,
        label=f"critical wear {data.critical_wear_m * UM:.2f} um",
    )
    ax_w.axvline(
        data.lip_wear_m * UM, color="grey", ls="--", label="lip allowance (K_i2 > 0 beyond)"
    )
    ax_w.set(xlabel="seal wear (um)", ylabel="cut-off frequency (Hz)", title="cut-off vs wear")
    for ax in (ax_k, ax_w):
        ax.axhline(
            data.critical_cutoff_hz,
            color="red",
            ls=":",
            label=f"{data.drop:.0%} below healthy ({data.healthy_cutoff_hz:.2f} Hz)",
        )
    for ax in (ax_m, ax_p, ax_k, ax_w):
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    return _save(fig, path)


def _zoom_limits(values: np.ndarray, margin: float = 0.3) -> tuple[float, float]:
    lo, hi = float(np.min(values)), float(np.max(values))
    pad = margin * max(hi - lo, 1e-12)
    return lo - pad, hi + pad


def plot_fig7a_null_bias(data: NullBiasCurves, path: str | os.PathLike[str]) -> Figure:
    """Fig. 7a: pre-flight test currents with a cracked spring and the null bias vs depth."""
    fig = _new_figure(
        2, 2, (11.0, 7.5), "Paper Fig. 7a: servovalve current, healthy and cracked spring"
    )
    ax_x, ax_z, ax_i, ax_b = fig.axes
    ax_x.plot(data.t_s, data.command_m * MM, color="k")
    ax_x.set(xlabel="time (s)", ylabel="SCAS command (mm)", title="pre-flight test command")
    colors = _colors(data.trace_depth_m.size)
    for color, depth, current in zip(colors, data.trace_depth_m, data.current_a, strict=True):
        label = f"a = {depth * MM:.2f} mm"
        ax_i.plot(data.t_s, current * MA, color=color, lw=1.0, label=label)
        ax_z.plot(data.t_s, current * UA, color=color, lw=1.2, label=label)
    ax_i.set(xlabel="time (s)", ylabel="current i (mA)", title="servovalve current (noise off)")
    ax_z.set_ylim(*_zoom_limits(data.null_bias_a * UA, margin=0.5))
    ax_z.set(
        xlabel="time (s)",
        ylabel="current i (uA)",
        title="zoom on the zero-command plateaus (null bias)",
    )
    ax_b.plot(data.depth_m * MM, data.null_bias_a * UA, "o-", color="k", ms=4)
    ax_b.axvline(data.failure_depth_m * MM, color="red", ls=":", label="failure depth")
    ax_b.set(
        xlabel="crack depth a (mm)",
        ylabel="null-bias current (uA)",
        title="mean current on the settled zero plateaus",
    )
    for ax in (ax_x, ax_z, ax_i, ax_b):
        ax.grid(alpha=0.3)
    ax_z.legend(fontsize=7, loc="center", bbox_to_anchor=(0.33, 0.5))  # the off-scale gap
    for ax in (ax_i, ax_b):
        ax.legend(fontsize=7)
    return _save(fig, path)


def plot_fig7b_seal_gain(data: SealGainCurves, path: str | os.PathLike[str]) -> Figure:
    """Fig. 7b: pre-flight test current and position with worn seals, gain vs wear."""
    fig = _new_figure(
        2, 2, (11.0, 7.5), "Paper Fig. 7b: servovalve current and position, worn seals"
    )
    ax_i, ax_z, ax_x, ax_g = fig.axes
    colors = _colors(data.trace_wear_m.size)
    top = int(np.argmax(data.command_m))
    plateau = data.command_m == data.command_m[top]
    for color, wear, current, position in zip(
        colors, data.trace_wear_m, data.current_a, data.position_m, strict=True
    ):
        label = f"wear {wear * UM:.1f} um ({wear / data.critical_wear_m:.1f} x critical)"
        ax_i.plot(data.t_s, current * MA, color=color, lw=1.0, label=label)
        ax_x.plot(data.t_s, position * MM, color=color, lw=1.0, label=label)
        ax_z.plot(data.t_s[plateau], position[plateau] * MM, color=color, label=label)
    ax_x.plot(data.t_s, data.command_m * MM, "k--", lw=0.8, label="command")
    ax_z.axhline(data.command_m[top] * MM, color="k", ls="--", lw=0.8, label="command")
    ax_i.set(xlabel="time (s)", ylabel="current i (mA)", title="servovalve current (noise off)")
    ax_x.set(xlabel="time (s)", ylabel="position x (mm)", title="actuator position")
    ax_z.set(
        xlabel="time (s)",
        ylabel="position x (mm)",
        title=f"zoom on the {data.command_m[top] * MM:g} mm plateau",
    )
    ax_g.plot(data.wear_m * UM, data.gain, "o-", color="k", ms=4)
    ax_g.axvline(data.critical_wear_m * UM, color="red", ls=":", label="critical wear")
    ax_g.set(
        xlabel="seal wear (um)",
        ylabel=f"servo gain |X/X_cmd| at {data.gain_frequency_hz:g} Hz (-)",
        title="servo gain loss with wear",
    )
    for ax in (ax_i, ax_z, ax_x, ax_g):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    return _save(fig, path)


def plot_demo_condition(
    runs: Mapping[str, ActuatorRun], path: str | os.PathLike[str], *, title: str
) -> Figure:
    """Current and position of one condition, one line per health state (demo)."""
    if not runs:
        raise ValueError("runs must hold at least one health state")
    fig = _new_figure(2, 1, (10.0, 6.5), title)
    ax_i, ax_x = fig.axes
    for color, (name, run) in zip(_colors(len(runs)), runs.items(), strict=True):
        ax_i.plot(run.t_s, run.current_a * MA, color=color, lw=0.7, label=name)
        ax_x.plot(run.t_s, run.lvdt_m * MM, color=color, lw=0.7, label=f"{name} (LVDT)")
    first = next(iter(runs.values()))
    ax_x.plot(first.t_s, first.command_m * MM, "k--", lw=0.8, label="command")
    ax_i.set(xlabel="time (s)", ylabel="servovalve current i (mA)")
    ax_x.set(xlabel="time (s)", ylabel="position x (mm)")
    for ax in (ax_i, ax_x):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return _save(fig, path)


#: File stem and plot function of each paper figure.
PAPER_PLOTS = {
    "fig3": ("fig3_spring_rate", plot_fig3_spring_rate),
    "fig4": ("fig4_crack_growth", plot_fig4_crack_growth),
    "fig5": ("fig5_frequency_response", plot_fig5_frequency_response),
    "fig7a": ("fig7a_null_bias", plot_fig7a_null_bias),
    "fig7b": ("fig7b_seal_gain", plot_fig7b_seal_gain),
}


def save_paper_figures(
    figs: PaperFigures,
    out_dir: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    seed: int | None = None,
) -> list[Path]:
    """Write one PNG per paper figure and ``figures.json`` (all curves) as the results
    folder ``out_dir``, atomically and with ``manifest.json``
    (:func:`scas_env.utils.results_folder.results_folder`; ``seed``, the Fig. 4 load
    spectrum's, goes into its seeds). An existing non-empty folder is refused unless
    ``overwrite`` and written by this package (then replaced whole). Returns the written
    files' paths (the manifest excluded)."""
    out = Path(out_dir)
    names = [f"{stem}.png" for stem, _ in PAPER_PLOTS.values()] + ["figures.json"]
    config = {"figures": list(PAPER_PLOTS)}
    with results_folder(out, config=config, seeds={"fig4": seed}, overwrite=overwrite) as tmp:
        for name, (stem, plot) in PAPER_PLOTS.items():
            plot(getattr(figs, name), tmp / f"{stem}.png")
        (tmp / "figures.json").write_text(json_text(figs.to_dict()))
    return [out / name for name in names]


# --- command line -----------------------------------------------------------------------

log = logging.getLogger(__name__)

COMMAND_DOC = """\
Paper physics figures (Figs. 3, 4, 5, 7a, 7b): one PNG each plus figures.json.

See experiments.paper.figure_data.paper_figures and figures.save_paper_figures. Example:

    python -m experiments.paper.figures --out results/figures
"""


def build_parser() -> argparse.ArgumentParser:
    """The command's parser (``--help``: docs/cli.md)."""
    from experiments.cli_common import add_params_arg
    from scas_env.cli_args import add_logging_args, make_parser, nonneg_int

    parser = make_parser("python -m experiments.paper.figures", COMMAND_DOC)
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    parser.add_argument(
        "--seed", type=nonneg_int, default=0, help="seed of the Fig. 4 load spectrum"
    )
    add_params_arg(parser)
    add_logging_args(parser)
    return parser


@keeps_results
def main(argv: Sequence[str] | None = None) -> int:
    """Compute the figures' data and write one PNG per figure and ``figures.json``."""
    from experiments.cli_common import load_params
    from scas_env.cli_args import check_out_dir, configure_logging

    parser = build_parser()
    args = parser.parse_args(argv)
    configure_logging(args)
    check_out_dir(parser, args.out, args.overwrite)
    params = load_params(parser, args)
    start = time.perf_counter()
    figs = paper_figures(params, np.random.default_rng(args.seed))
    computed = time.perf_counter() - start
    paths = save_paper_figures(figs, args.out, overwrite=args.overwrite, seed=args.seed)
    for path in paths:
        log.info(f"wrote {path}")
    log.info(f"computed in {computed:.1f} s, total {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
