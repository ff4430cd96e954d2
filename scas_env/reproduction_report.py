"""Report of a :class:`~scas_env.reproduction.Reproduction`: verdicts, tables and figures.

:func:`verdicts` compares every result [DJS20] states in §4-5 with ours and labels it
"holds" or "differs" with a one-line reason. Rules: a feature choice or a direction holds
when it is the same; a detection severity holds within +-0.10 of the paper's value (fraction
of critical); a minimum RA holds at or above the paper's bound; a final CRA holds when at
least the paper's value minus 0.05. Prognosis numbers are means over the paths of a fault.

:func:`write_report` writes ``report.json`` and ``report.md``, the figures ``fig8_crack.png``,
``fig8_wear.png`` (accuracy-sensitivity plane, ground and flight candidates),
``fig9_crack.png``, ``fig9_wear.png`` (first path: severity tracking and RUL with the
alpha = 0.2 cone) and ``ra_over_time.png``, and the numbers behind each figure as CSV
(``fig8_<fault>.csv``, ``fig9_<fault>.csv``; the RA curve is a column of the latter).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from prognostics.selection import plot_accuracy_sensitivity
from scas_env.reproduction import FAULTS, PathPrognosis, Reproduction

__all__ = ["PAPER", "verdicts", "write_report"]

PAPER: dict[str, Any] = {
    "crack": {"ground": "G3", "flight": "I2", "g3": "rising", "detect": 0.25, "ra": 0.80},
    "wear": {"ground": "G3", "flight": "I6", "g3": "falling", "detect": 0.09, "ra": 0.90},
    "cra": {"crack": 0.86, "wear": 0.94},
}
"""[DJS20] §4-5 results (reference sheet §0.6-0.10)."""

DETECTION_TOLERANCE = 0.10
CRA_TOLERANCE = 0.05
_NAMES = {"crack": "spring crack", "wear": "seal wear"}


def _fmt(value: float, digits: int = 2) -> str:
    return "n.d." if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def _row(claim: str, paper: Any, ours: Any, holds: bool, reason: str) -> dict[str, Any]:
    return {
        "claim": claim,
        "paper": paper,
        "ours": ours,
        "verdict": "holds" if holds else "differs",
        "reason": reason,
    }


def detection_severity(rep: Reproduction, fault: str) -> float:
    """Mean severity at detection over the campaign paths; a path that never alarms counts
    as NaN, so the mean is NaN unless every path detects (see :func:`detected_share`)."""
    return float(np.mean(rep.detection[fault]["combined_severity_at_detection"]))


def detected_share(rep: Reproduction, fault: str) -> str:
    """``"<mean over detecting paths> (<k>/<n> paths)"`` for the report."""
    values = np.array(rep.detection[fault]["combined_severity_at_detection"])
    hit = values[np.isfinite(values)]
    mean = float(hit.mean()) if hit.size else math.nan
    return f"{_fmt(mean)} ({hit.size}/{values.size} paths)"


def prognosis_summary(paths: list[PathPrognosis]) -> dict[str, float]:
    """Means over paths of min RA, final CRA, prognostic horizon and detection severity."""
    det = [
        p.test_severity_m[p.detection_index] / p.path.threshold_m
        for p in paths
        if p.detection_index is not None
    ]
    return {
        "min_ra": float(np.mean([p.metrics.min_relative_accuracy for p in paths])),
        "cra": float(np.mean([p.metrics.cumulative_relative_accuracy for p in paths])),
        "prognostic_horizon_flights": float(
            np.nanmean([p.metrics.prognostic_horizon for p in paths])
        )
        if any(math.isfinite(p.metrics.prognostic_horizon) for p in paths)
        else math.nan,
        "detected_paths": float(len(det) / len(paths)),
        "severity_at_detection": float(np.mean(det)) if det else math.nan,
    }


def verdicts(rep: Reproduction) -> list[dict[str, Any]]:
    """One row per paper result: claim, paper value, ours, verdict, reason (module doc)."""
    sel = rep.selection
    rows = []
    red = [
        next(
            (
                p
                for p in sel["redundancy"][f"{f}/flight"]["pairs"]
                if {p["first"], p["second"]} == {"I5", "I6"}
            ),
            None,
        )
        for f in FAULTS
    ]
    ours = "; ".join(
        f"{f}: J={p['divergence_nats']:.1e} nats, r={p['run_correlation']:.4f}" if p else f"{f}: no"
        for f, p in zip(FAULTS, red, strict=True)
    )
    rows.append(
        _row(
            "I5/I6 redundant, I5 dropped",
            "yes",
            ours,
            all(red) and "I5" in sel["pruned"]["flight"],
            f"I5 = I6 by Parseval (unitary DFT); also pruned: {sel['pruned']['flight']}",
        )
    )
    for fault in FAULTS:
        chosen, paper = sel["selected"][fault], PAPER[fault]
        top = chosen["ground_per_fault_top"]
        rows.append(
            _row(
                f"{_NAMES[fault]}: ground feature",
                paper["ground"],
                chosen["ground"],
                chosen["ground"] == paper["ground"],
                f"one pre-flight feature for both faults (maximin of accuracy x |rho|); "
                f"per-fault ranking puts {top} first",
            )
        )
        flight = next(s for s in sel["scores"][f"{fault}/flight"] if s.name == chosen["flight"])
        reason = (
            f"{flight.name}: rho={flight.spearman:.2f}, SNR={flight.snr_db:.1f} dB"
            + ("" if chosen["flight_responsive"] else "; no in-flight feature responds")
            + (
                ": random-amplitude flight commands swamp the crack's small null bias"
                if fault == "crack"
                else ": leakage barely changes the in-flight motion below critical"
            )
        )
        rows.append(
            _row(
                f"{_NAMES[fault]}: flight feature",
                paper["flight"],
                chosen["flight"],
                chosen["flight"] == paper["flight"],
                reason,
            )
        )
    g3 = {f: next(s for s in sel["scores"][f"{f}/ground"] if s.name == "G3") for f in FAULTS}
    rows.append(
        _row(
            "G3 moves in opposite directions with the two faults",
            "yes",
            f"crack {g3['crack'].direction}, wear {g3['wear'].direction}",
            g3["crack"].direction != g3["wear"].direction,
            "the crack's null-bias current and the leakage's gain loss act with opposite signs",
        )
    )
    reasons = {
        "crack": "cracked spring 0 is the one compressed by the test's positive step: its "
        "null-bias current lowers i/x on the asymmetric plateaus",
        "wear": "leakage needs more current per mm of stroke (gain loss), so i/x rises",
    }
    for fault in FAULTS:
        rows.append(
            _row(
                f"G3 direction with {_NAMES[fault]}",
                PAPER[fault]["g3"],
                f"{g3[fault].direction} (SNR {g3[fault].snr_db:.1f} dB)",
                g3[fault].direction == PAPER[fault]["g3"],
                reasons[fault],
            )
        )
    det = {f: detection_severity(rep, f) for f in FAULTS}
    prog = {f: prognosis_summary(rep.prognosis[f]) for f in FAULTS}
    for fault in FAULTS:
        paper = PAPER[fault]["detect"]
        ours_det = det[fault]
        rows.append(
            _row(
                f"{_NAMES[fault]}: severity at detection",
                paper,
                f"campaign paths {detected_share(rep, fault)}; prognosis paths "
                f"{_fmt(prog[fault]['severity_at_detection'])}",
                math.isfinite(ours_det) and abs(ours_det - paper) <= DETECTION_TOLERANCE,
                "population baseline: unit-to-unit scatter of G3 (spring tolerances, fluid "
                "temperature) hides the early signature",
            )
        )
    crack_det = det["crack"] if math.isfinite(det["crack"]) else math.inf
    rows.append(
        _row(
            "seal wear detected earlier than the crack",
            "yes (9% vs 25%)",
            f"{_fmt(det['wear'])} vs {_fmt(det['crack'])}",
            math.isfinite(det["wear"]) and det["wear"] < crack_det,
            "G3 rises > 5 healthy sigma with wear, falls 2-3 sigma with the crack",
        )
    )
    for fault in FAULTS:
        bound = PAPER[fault]["ra"]
        rows.append(
            _row(
                f"{_NAMES[fault]}: min RA",
                f">= {bound}",
                _fmt(prog[fault]["min_ra"]),
                prog[fault]["min_ra"] >= bound,
                "G3 is nearly flat until ~half the critical severity, so the growth "
                "multiplier is learnt late; RUL errors peak near the end of life",
            )
        )
        cra = PAPER["cra"][fault]
        rows.append(
            _row(
                f"{_NAMES[fault]}: final CRA",
                cra,
                _fmt(prog[fault]["cra"]),
                prog[fault]["cra"] >= cra - CRA_TOLERANCE,
                f"mean over {len(rep.prognosis[fault])} path(s)",
            )
        )
    return rows


# ----------------------------------------------------------------------------- figures
def _fig9(p: PathPrognosis, path: Path) -> None:
    tr, thr = p.trace, p.path.threshold_m
    fig = Figure(figsize=(7.0, 6.4))
    FigureCanvasAgg(fig)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    flights = np.arange(p.path.severity_m.size)
    ax1.plot(flights, p.path.severity_m / thr, "k-", lw=1, label="true severity")
    ax1.errorbar(
        tr.times,
        tr.x_mean / thr,
        yerr=2 * tr.x_std / thr,
        fmt=".",
        ms=3,
        alpha=0.5,
        label="PF estimate +- 2 sigma",
    )
    if p.detection_index is not None:
        ax1.axvline(tr.times[p.detection_index], color="tab:red", ls=":", label="detection")
    ax1.set_ylabel("severity / critical")
    ax1.legend(fontsize=8)
    s = tr.start_index
    t, eol = tr.times[s:], float(p.path.eol_flights)
    true_rul = eol - t
    ax2.plot(t, true_rul, "k-", label="true RUL")
    ax2.fill_between(t, 0.8 * true_rul, 1.2 * true_rul, color="0.85", label="alpha = 0.2 cone")
    ax2.fill_between(
        t, tr.rul_low[s:], tr.rul_high[s:], color="tab:blue", alpha=0.25, label="5-95% RUL"
    )
    ax2.plot(t, tr.rul_mean[s:], color="tab:blue", label="mean RUL")
    ax2.axvline(p.eoup_flights, color="0.5", ls="--", label="end of useful predictions")
    ax2.set_xlabel("flights")
    ax2.set_ylabel("RUL (flights)")
    ax2.set_ylim(0, 1.6 * true_rul[0])
    ax2.legend(fontsize=8)
    fig.suptitle(f"Prognosis, {_NAMES[p.path.fault]} (theta = {p.path.theta:.2f})")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _ra_plot(rep: Reproduction, path: Path) -> None:
    fig = Figure(figsize=(6.4, 4.0))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for fault, color in zip(FAULTS, ("tab:red", "tab:blue"), strict=True):
        p = rep.prognosis[fault][0]
        t = p.trace.times[p.trace.start_index :][: p.metrics.relative_accuracy.size]
        ax.plot(
            t / p.path.eol_flights,
            p.metrics.relative_accuracy,
            color=color,
            label=f"{_NAMES[fault]} (CRA {p.metrics.cumulative_relative_accuracy:.2f})",
        )
        ax.axhline(PAPER[fault]["ra"], color=color, ls=":", lw=1)
    ax.set_xlabel("life fraction t / t_EoL")
    ax.set_ylabel("relative accuracy")
    ax.set_ylim(min(0.0, ax.get_ylim()[0]), 1.05)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _write_csv(path: Path, header: list[str], rows: list[list[Any]]) -> None:
    with path.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)


def _fig9_rows(p: PathPrognosis) -> list[list[Any]]:
    tr, eol = p.trace, float(p.path.eol_flights)
    ra = np.full(tr.times.size, math.nan)
    ra[tr.start_index : tr.start_index + p.metrics.relative_accuracy.size] = (
        p.metrics.relative_accuracy
    )
    return [
        [
            tr.times[j],
            p.test_severity_m[j],
            p.measurements[j],
            bool(p.alarms[j]),
            tr.x_mean[j],
            tr.x_std[j],
            tr.theta_mean[j],
            eol - tr.times[j],
            tr.rul_mean[j],
            tr.rul_median[j],
            tr.rul_low[j],
            tr.rul_high[j],
            ra[j],
        ]
        for j in range(tr.times.size)
    ]


def _json_ready(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_ready(v) for v in value]
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer | np.bool_):
        return value.item()
    if hasattr(value, "__dataclass_fields__"):
        return _json_ready(dict(vars(value)))
    return value


def report_dict(rep: Reproduction, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Everything of the report as JSON-ready data (no particle samples)."""
    paths = {
        fault: [
            {
                "theta": p.path.theta,
                "initial_severity_m": float(p.path.severity_m[0]),
                "eol_flights": p.path.eol_flights,
                "test_interval_flights": p.test_interval,
                "n_tests": int(p.test_flights.size),
                "detection_test": p.detection_index,
                "prediction_start_flight": float(p.trace.times[p.trace.start_index]),
                "eoup_flights": p.eoup_flights,
                "unit_gain": p.unit_gain,
                "min_ra": p.metrics.min_relative_accuracy,
                "cra": p.metrics.cumulative_relative_accuracy,
                "alpha_lambda": p.metrics.alpha_lambda,
                "prognostic_horizon_flights": p.metrics.prognostic_horizon,
                "convergence": p.metrics.convergence,
            }
            for p in rep.prognosis[fault]
        ]
        for fault in FAULTS
    }
    sel = {k: v for k, v in rep.selection.items() if k != "scores"}
    sel["scores"] = {k: [vars(s) for s in v] for k, v in rep.selection["scores"].items()}
    return _json_ready(
        {
            "seed": rep.seed,
            "config": rep.config.to_dict(),
            "campaign": {"n_rows": rep.campaign.n_rows, **rep.campaign.metadata["config"]},
            "verdicts": verdicts(rep),
            "selection": sel,
            "detection": rep.detection,
            "healthy_unit_alarm_share": rep.healthy_unit_alarm_share,
            "prognosis": {
                f: {"summary": prognosis_summary(rep.prognosis[f]), "paths": paths[f]}
                for f in FAULTS
            },
            "timings_s": rep.timings_s,
            **(extra or {}),
        }
    )


def _markdown(report: dict[str, Any]) -> str:
    lines = [
        "# Reproduction of [DJS20] sections 4-5",
        "",
        f"Seed {report['seed']}; campaign {report['campaign']['n_runs']} runs x "
        f"{report['campaign']['n_levels']} levels; {report['config']['n_paths']} prognosis "
        f"path(s) per fault.",
        "",
        "| result | paper | ours | verdict | reason |",
        "|---|---|---|---|---|",
    ]
    for r in report["verdicts"]:
        lines.append(
            f"| {r['claim']} | {r['paper']} | {r['ours']} | {r['verdict']} | {r['reason']} |"
        )
    lines += [
        "",
        "Per-unit false alarm (share of healthy units alarming on their first window): "
        + ", ".join(f"{k} detector {v:.2f}" for k, v in report["healthy_unit_alarm_share"].items()),
    ]
    for key in ("wall_s", "command"):
        if key in report:
            lines.append(f"{key}: {report[key]}")
    return "\n".join(lines) + "\n"


def write_report(
    rep: Reproduction, out_dir: str | Path, extra: dict[str, Any] | None = None
) -> list[Path]:
    """Write report.json, report.md, the figures and their CSVs into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for fault in FAULTS:
        scores = (
            rep.selection["scores"][f"{fault}/ground"] + rep.selection["scores"][f"{fault}/flight"]
        )
        png = out / f"fig8_{fault}.png"
        plot_accuracy_sensitivity(scores, png, title=f"Feature selection: {_NAMES[fault]}")
        fields = list(vars(scores[0]))
        _write_csv(out / f"fig8_{fault}.csv", fields, [list(vars(s).values()) for s in scores])
        p = rep.prognosis[fault][0]
        _fig9(p, out / f"fig9_{fault}.png")
        header = [
            "flight",
            "true_severity_m",
            "feature",
            "alarm",
            "x_mean_m",
            "x_std_m",
            "theta_mean",
            "true_rul",
            "rul_mean",
            "rul_median",
            "rul_p05",
            "rul_p95",
            "ra",
        ]
        _write_csv(out / f"fig9_{fault}.csv", header, _fig9_rows(p))
        written += [
            png,
            out / f"fig8_{fault}.csv",
            out / f"fig9_{fault}.png",
            out / f"fig9_{fault}.csv",
        ]
    _ra_plot(rep, out / "ra_over_time.png")
    report = report_dict(rep, extra)
    (out / "report.json").write_text(json.dumps(report, indent=1) + "\n")
    (out / "report.md").write_text(_markdown(report))
    return [*written, out / "ra_over_time.png", out / "report.json", out / "report.md"]
