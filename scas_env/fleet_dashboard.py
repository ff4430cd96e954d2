"""The fleet's dashboard (``render_mode="rgb_array"`` of ``ScasFleet-v0``): one row per
aircraft with its actuators' health and risk, the spares and the crew's day.

Left: a row per aircraft, a cell per actuator and part, coloured by the monitor's
probability of failure within the risk horizon (white 0, red 1), with the part's true wear
fraction written in it, and the aircraft's status (free, hangar, broken, mission flown
today). Right: spares on hand and on order per kind, jobs waiting, the crew's jobs a day,
missions flown and asked so far. matplotlib is imported here only (Agg canvas).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from scas_env.core.fleet import FleetBatch
from scas_env.core.fleet_view import FleetView
from scas_env.core.resources import SPARE_KINDS
from scas_env.core.setup import PARTS

#: frame size (pixels) = FIGSIZE_IN * DPI
FIGSIZE_IN = (8.0, 5.0)
DPI = 80


def draw_fleet(fleet: FleetBatch, view: FleetView, b: int = 0) -> np.ndarray:
    """An (H, W, 3) uint8 frame of fleet ``b`` (module docstring)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    sh, a = fleet.shape, fleet.actuators.a
    values = view.groups(b)
    rows = fleet.rows_of(b)
    fleet.actuators.refresh(rows)
    risk = _risks(fleet, view, rows).reshape(sh.aircraft, sh.actuators * 2)
    severity = np.column_stack(
        [a["crack"][rows] / a["fail"][rows], a["wear"][rows] / fleet.setup.world.seal_critical_m]
    ).reshape(sh.aircraft, sh.actuators * 2)
    fig = Figure(figsize=FIGSIZE_IN, dpi=DPI)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.12, 0.1, 0.5, 0.8))
    ax.imshow(risk, cmap="Reds", vmin=0.0, vmax=1.0, aspect="auto")
    for i in range(sh.aircraft):
        for c in range(sh.actuators * 2):
            ax.text(c, i, f"{severity[i, c]:.0%}", ha="center", va="center", fontsize=7)
    ax.set_xticks(range(sh.actuators * 2))
    ax.set_xticklabels([f"A{j} {p[:2]}" for j in range(sh.actuators) for p in PARTS], fontsize=7)
    status = values["aircraft"]
    flown = fleet.today["completed"][b]
    labels = []
    for i in range(sh.aircraft):
        s = "free" if status[i, 4] else ("broken" if status[i, 1] else "hangar")
        labels.append(f"{i}: {s}{' *' if flown[i] else ''}")
    ax.set_yticks(range(sh.aircraft))
    ax.set_yticklabels(labels, fontsize=7)
    ax.set_title(f"day {int(fleet.day[b])}: risk (colour), severity (text); * flew", fontsize=8)
    side = fig.add_axes((0.68, 0.1, 0.3, 0.8))
    side.axis("off")
    res = values["resources"]
    books = fleet.books
    lines = [f"{k}: {int(res[n])} on hand, {int(res[3 + n])} on order"
             for n, k in enumerate(SPARE_KINDS)]  # fmt: skip
    lines += [
        f"jobs waiting: {int(res[6])}",
        f"crew jobs/day: {int(res[7]) or 'unlimited'}",
        f"missions: {int(books['missions_flown'][b])}/{int(books['missions_demanded'][b])}",
        f"failures: {int(a['failures'][rows].sum())}",
        f"background removals: {int(books['background_removals'][b])}",
    ]
    side.text(0.0, 1.0, "\n".join(lines), va="top", fontsize=8, family="monospace")
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def _risks(fleet: FleetBatch, view: FleetView, rows: np.ndarray) -> np.ndarray:
    """(rows, 2) probability of failure within the horizon of each part (the monitor's)."""
    from scas_env.core.observation import ageing_estimates

    a, s = fleet.actuators.a, fleet.setup.scenario
    est = np.empty((rows.size, 2, 3))
    ageing_estimates(
        a["rul_sorted"][rows], a["rul_cum_w"][rows], a["rul_suffix_w"][rows],
        a["rul_suffix_wr"][rows], a["rul_low"][rows], a["pending"][rows],
        float(s.risk_horizon_flights), float(s.rul_cap_flights), est,
    )  # fmt: skip
    return est[:, :, 2]


def render_text(info: dict[str, Any]) -> str:
    """One line of a fleet's day (``render_mode="ansi"``)."""
    return (
        f"day {info['day']}: missions {info['missions_flown']}/{info['missions_demanded']}, "
        f"failures {sum(info['failures'].values())}, jobs waiting {info['jobs_waiting']}, "
        f"cost {info['cost_usd']:,.0f} USD"
    )


__all__ = ["draw_fleet", "render_text"]
