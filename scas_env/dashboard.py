"""Health dashboard of one actuator: an RGB frame of crack, wear, RUL, features and costs.

Three pieces, so that drawing never reaches into the env:

* :class:`HealthRecord`: a frozen, plain data record of everything a frame shows (the
  history of crack and wear as fractions of their critical levels, the particle filters'
  RUL distributions, the latest features, costs and availability so far);
* :class:`HealthDashboard`: a persistent matplotlib figure on the Agg canvas, updated in
  place from a record (no pyplot, no global state): :meth:`HealthDashboard.draw` returns an
  ``(H, W, 3)`` uint8 frame. The same record gives the same pixels;
* :func:`frame_record_from_env` builds a record from a running env, with a
  :class:`HealthTrace` that collected the history step by step; :class:`DashboardRenderer`
  bundles trace, figure and the env's ``render_mode`` (``"rgb_array"`` or ``"human"``).

matplotlib is imported inside :class:`HealthDashboard` only (the env layer does not need
it otherwise). Frame cost: ``python -m experiments.dashboard_speed`` (docs/dashboard.md).

The env is read through row 0 of its batch (``env.unwrapped.batch``, the
:class:`~scas_env.core.batch.ActuatorBatch` of the single env), all in the small functions
:func:`critical_levels`, :func:`unit_growth_multipliers`, :func:`rul_distribution`,
:func:`episode_totals`, :func:`true_state` and :func:`latest_features`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from scas_env.core.observation import FEATURE_UNITS, FEATURES
from scas_env.core.setup import PARTS

#: central interval of the RUL distributions drawn (probability levels)
INTERVAL = (0.05, 0.95)
#: bins of the RUL histograms
RUL_BINS = 40
#: frame size (pixels) = FIGSIZE_IN * DPI
FIGSIZE_IN = (8.0, 5.0)
DPI = 80
COLORS = {"spring": "#1f77b4", "seal": "#d62728"}


# ---------------------------------------------------------------------------- record
@dataclass(frozen=True, eq=False)
class PartRul:
    """A part's RUL distribution (flights): weighted samples and the true RUL.

    Attributes
    ----------
    samples_flights : RUL of each particle (flights, >= 0), shape (N,).
    weights : their weights (>= 0, sum 1), shape (N,).
    true_flights : the true RUL (flights; ``inf`` if the fault never grows).
    """

    samples_flights: np.ndarray
    weights: np.ndarray
    true_flights: float

    def __post_init__(self) -> None:
        r = _frozen_array("PartRul.samples_flights", self.samples_flights)
        w = _frozen_array("PartRul.weights", self.weights)
        if r.shape != w.shape or r.ndim != 1 or r.size == 0:
            raise ValueError(
                f"PartRul: samples_flights {r.shape} and weights {w.shape} must be equal, "
                "non-empty 1-d shapes"
            )
        if np.any(r < 0) or np.any(w < 0) or not math.isclose(float(w.sum()), 1.0, rel_tol=1e-9):
            raise ValueError("PartRul: samples must be >= 0, weights >= 0 summing to 1")
        if math.isnan(self.true_flights) or self.true_flights < 0:
            raise ValueError(f"PartRul.true_flights = {self.true_flights} must be >= 0")
        object.__setattr__(self, "samples_flights", r)
        object.__setattr__(self, "weights", w)

    def quantiles(self, levels: tuple[float, ...]) -> np.ndarray:
        """Weighted quantiles (inverted CDF, as :func:`prognostics.rul.weighted_quantile`)."""
        order = np.argsort(self.samples_flights, kind="stable")
        cum = np.cumsum(self.weights[order])
        idx = np.searchsorted(cum, np.asarray(levels) - 1e-12, side="left")
        return self.samples_flights[order][np.minimum(idx, len(cum) - 1)]

    @property
    def mean(self) -> float:
        return float(self.weights @ self.samples_flights)


@dataclass(frozen=True, eq=False)
class HealthRecord:
    """Everything one dashboard frame shows (plain data; see the module docstring).

    Attributes
    ----------
    slots : slot index of each history point (1-based; 0 = reset), shape (T,).
    crack_fraction, wear_fraction : true crack depth and wear over their critical levels
        at those points, shape (T,).
    crack_depth_m, seal_wear_m : current true values (m).
    spring_critical_m, seal_critical_m : critical crack depth and wear (m).
    rul : per part (``"spring"``, ``"seal"``) its :class:`PartRul`, or ``None`` when the
        observation shows no filter output (an ``obs_mode`` without RUL; the filters run).
    features : latest measured features ``(name, value, unit)`` in display units.
    cost_usd, revenue_usd : costs and flight revenue so far (USD).
    availability : flights flown / slots so far.
    flights, tests : flights flown and pre-flight tests so far.
    failures, replacements : per part, counts so far (failures included in replacements).
    downtime : slots still to spend on the ground.
    title : a label (e.g. fidelity and seed).
    """

    slots: np.ndarray
    crack_fraction: np.ndarray
    wear_fraction: np.ndarray
    crack_depth_m: float
    seal_wear_m: float
    spring_critical_m: float
    seal_critical_m: float
    rul: dict[str, PartRul] | None
    features: tuple[tuple[str, float, str], ...]
    cost_usd: float
    revenue_usd: float
    availability: float
    flights: int
    tests: int
    failures: dict[str, int] = field(default_factory=lambda: dict.fromkeys(PARTS, 0))
    replacements: dict[str, int] = field(default_factory=lambda: dict.fromkeys(PARTS, 0))
    downtime: int = 0
    title: str = ""

    def __post_init__(self) -> None:
        arrays = [
            _frozen_array(f"HealthRecord.{name}", getattr(self, name))
            for name in ("slots", "crack_fraction", "wear_fraction")
        ]
        if len({a.shape for a in arrays}) != 1 or arrays[0].ndim != 1 or arrays[0].size == 0:
            raise ValueError(
                "HealthRecord: slots, crack_fraction, wear_fraction must be equal, non-empty "
                f"1-d shapes, got {[a.shape for a in arrays]}"
            )
        for name, a in zip(("slots", "crack_fraction", "wear_fraction"), arrays, strict=True):
            object.__setattr__(self, name, a)
        for name in ("spring_critical_m", "seal_critical_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"HealthRecord.{name} = {getattr(self, name)} must be > 0")
        if self.rul is not None and set(self.rul) != set(PARTS):
            raise ValueError(f"HealthRecord.rul must have the keys {PARTS}, got {set(self.rul)}")
        if not 0.0 <= self.availability <= 1.0:
            raise ValueError(f"HealthRecord.availability = {self.availability} must be in [0, 1]")


def _frozen_array(name: str, value: Any) -> np.ndarray:
    a = np.array(value, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    a.setflags(write=False)
    return a


# ---------------------------------------------------------------------------- env access
def critical_levels(env: Any) -> tuple[float, float]:
    """(critical crack depth of the fitted spring, critical seal wear), m."""
    u = env.unwrapped
    return float(u.batch.a["fail"][0]), float(u.calibration.seal_critical_wear_m)


def unit_growth_multipliers(env: Any) -> tuple[float, float]:
    """True growth multipliers of the fitted parts: (C_unit / C_nom, k_w,unit / k_w,nom)."""
    a = env.unwrapped.batch.a
    return float(a["theta"][0]), float(a["wmult"][0])


def rul_distribution(env: Any, part: str) -> tuple[np.ndarray, np.ndarray]:
    """``part``'s particle-filter RUL now (flights): (samples, weights summing to 1); the
    distribution at the filter's last update aged by the flights flown since."""
    batch = env.unwrapped.batch
    batch.refresh(np.zeros(1, dtype=np.int64))
    p = PARTS.index(part)
    a = batch.a
    weights = np.diff(a["rul_cum_w"][0, p])
    return (
        np.maximum(a["rul_sorted"][0, p] - float(a["pending"][0, p]), 0.0),
        weights / weights.sum(),
    )


def episode_totals(env: Any) -> dict[str, Any]:
    """Costs, revenue, counts and downtime of the episode so far."""
    a = env.unwrapped.batch.a
    return {
        "slot": int(a["slot"][0]),
        "cost_usd": float(a["cost"][0]),
        "revenue_usd": float(a["revenue"][0]),
        "flights": int(a["flown"][0]),
        "tests": int(a["tests"][0]),
        "failures": {p: int(a["failures"][0, k]) for k, p in enumerate(PARTS)},
        "replacements": {p: int(a["replacements"][0, k]) for k, p in enumerate(PARTS)},
        "downtime": int(a["downtime"][0]),
    }


def true_state(env: Any) -> dict[str, float]:
    """The truth now: crack depth and wear (m), their fractions of critical, each part's
    remaining life (flights, the failing one included; ``inf`` if the fault never grows)."""
    u = env.unwrapped
    a = u.batch.a
    crack, wear = float(a["crack"][0]), float(a["wear"][0])
    return {
        "crack_depth_m": crack,
        "seal_wear_m": wear,
        "crack_fraction": crack / float(a["fail"][0]),
        "wear_fraction": wear / float(u.calibration.seal_critical_wear_m),
        "spring_rul_flights": float(a["life"][0, 0]),
        "seal_rul_flights": float(a["life"][0, 1]),
    }


def latest_features(env: Any) -> dict[str, float]:
    """Latest measured features (SI units; healthy means before the first measurement)."""
    last = env.unwrapped.batch.a["last"][0]
    return {f: float(v) for f, v in zip(FEATURES, last.tolist(), strict=True)}


class HealthTrace:
    """History of the true crack and wear fractions, one point per :meth:`record`."""

    def __init__(self) -> None:
        self.slots: list[int] = []
        self.crack: list[float] = []
        self.wear: list[float] = []

    def clear(self) -> None:
        self.slots.clear()
        self.crack.clear()
        self.wear.clear()

    def record(self, env: Any) -> None:
        """Append the env's current state (a new episode, slot 0, clears the history)."""
        slot = int(env.unwrapped.slot)
        if slot == 0:
            self.clear()
        truth = true_state(env)
        self.slots.append(slot)
        self.crack.append(truth["crack_fraction"])
        self.wear.append(truth["wear_fraction"])


def frame_record_from_env(
    env: Any, trace: HealthTrace | None = None, *, title: str = ""
) -> HealthRecord:
    """The record of ``env``'s current state; the history is ``trace``'s (default: the
    current point only)."""
    u = env.unwrapped
    spring_crit, seal_crit = critical_levels(env)
    truth = true_state(env)
    t = episode_totals(env)
    if trace is None or not trace.slots:
        slots = [t["slot"]]
        crack, wear = [truth["crack_fraction"]], [truth["wear_fraction"]]
    else:
        slots, crack, wear = trace.slots, trace.crack, trace.wear
    rul = None
    if u.scenario.obs_mode in ("features+rul", "dict"):
        rul = {
            part: PartRul(*rul_distribution(env, part), true_flights=truth[f"{part}_rul_flights"])
            for part in PARTS
        }
    last = latest_features(env)
    features = tuple((f, last[f] * FEATURE_UNITS[f][1], FEATURE_UNITS[f][0]) for f in FEATURES)
    return HealthRecord(
        slots=np.asarray(slots),
        crack_fraction=np.asarray(crack),
        wear_fraction=np.asarray(wear),
        crack_depth_m=truth["crack_depth_m"],
        seal_wear_m=truth["seal_wear_m"],
        spring_critical_m=spring_crit,
        seal_critical_m=seal_crit,
        rul=rul,
        features=features,
        cost_usd=t["cost_usd"],
        revenue_usd=t["revenue_usd"],
        availability=t["flights"] / t["slot"] if t["slot"] else 1.0,
        flights=t["flights"],
        tests=t["tests"],
        failures=t["failures"],
        replacements=t["replacements"],
        downtime=t["downtime"],
        title=title,
    )


# ---------------------------------------------------------------------------- drawing
class HealthDashboard:
    """A persistent Agg figure drawing :class:`HealthRecord` frames (module docstring).

    >>> dash = HealthDashboard()
    >>> rec = HealthRecord(slots=[0, 1], crack_fraction=[0.1, 0.2], wear_fraction=[0.0, 0.1],
    ...     crack_depth_m=2e-4, seal_wear_m=1e-6, spring_critical_m=1e-3, seal_critical_m=1e-5,
    ...     rul=None, features=(), cost_usd=0.0, revenue_usd=0.0, availability=1.0,
    ...     flights=1, tests=0)
    >>> frame = dash.draw(rec)
    >>> frame.shape, frame.dtype
    ((400, 640, 3), dtype('uint8'))
    """

    def __init__(self, *, interactive: bool = False) -> None:
        if interactive:
            import matplotlib.pyplot as plt

            self.figure = plt.figure(figsize=FIGSIZE_IN, dpi=DPI)
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg
            from matplotlib.figure import Figure

            self.figure = Figure(figsize=FIGSIZE_IN, dpi=DPI)
            FigureCanvasAgg(self.figure)
        self.interactive = interactive
        self._build()

    def _build(self) -> None:
        fig = self.figure
        grid = fig.add_gridspec(
            2, 2, width_ratios=(1.6, 1.0), left=0.08, right=0.98, top=0.9, bottom=0.1,
            wspace=0.22, hspace=0.45,
        )  # fmt: skip
        self.suptitle = fig.suptitle("", fontsize=10)
        # history of crack and wear against the critical level
        ax = self.ax_history = fig.add_subplot(grid[0, 0])
        ax.axhline(1.0, color="k", lw=1.0, ls="--")
        ax.text(0.01, 1.02, "critical", transform=ax.get_yaxis_transform(), fontsize=7)
        (self.crack_line,) = ax.plot([], [], color=COLORS["spring"], lw=1.2, label="crack")
        (self.wear_line,) = ax.plot([], [], color=COLORS["seal"], lw=1.2, label="wear")
        ax.set(xlabel="slot", ylabel="fraction of critical")
        ax.set_title("true damage (crack depth, seal wear)", fontsize=9)
        ax.legend(loc="upper left", fontsize=7)
        # gauges: crack and wear now
        ax = self.ax_gauges = fig.add_subplot(grid[0, 1])
        self.bars = list(
            ax.barh([1, 0], [0.0, 0.0], color=[COLORS["spring"], COLORS["seal"]], height=0.6)
        )
        ax.axvline(1.0, color="k", lw=1.0, ls="--")
        ax.set(xlim=(0.0, 1.1), ylim=(-0.6, 1.6), yticks=[1, 0], xlabel="fraction of critical")
        ax.set_yticklabels(["crack", "wear"], fontsize=8)
        ax.set_title("now", fontsize=9)
        self.bar_labels = [ax.text(0.02, y, "", va="center", fontsize=7) for y in (1.4, 0.4)]
        # RUL distributions
        ax = self.ax_rul = fig.add_subplot(grid[1, 0])
        self.rul_stairs = {
            p: ax.stairs(
                np.zeros(RUL_BINS), np.linspace(0, 1, RUL_BINS + 1), fill=True, alpha=0.35,
                color=COLORS[p], label=p,
            )
            for p in PARTS
        }  # fmt: skip
        self.rul_interval = {
            p: ax.plot([], [], color=COLORS[p], lw=2.5, marker="|", ms=8)[0] for p in PARTS
        }
        self.rul_mean = {
            p: ax.plot([], [], ls="none", marker="o", color=COLORS[p], ms=5)[0] for p in PARTS
        }
        self.rul_true = {p: ax.axvline(0.0, color=COLORS[p], lw=1.2, ls=":") for p in PARTS}
        ax.set(ylim=(0.0, 1.35), yticks=[], xlabel="RUL (flights)")
        ax.set_title("filter RUL: density, mean (o), 90% interval (|-|), truth (:)", fontsize=9)
        ax.legend(loc="upper right", fontsize=7)
        self.rul_note = ax.text(0.5, 0.5, "", transform=ax.transAxes, ha="center", fontsize=9)
        # text panel: labels (static) and values (per frame)
        ax = self.ax_text = fig.add_subplot(grid[1, 1])
        ax.axis("off")
        style = {"va": "top", "family": "monospace", "fontsize": 7.5}
        self.labels = ax.text(0.0, 1.0, "", ha="left", **style)
        self.values = ax.text(1.0, 1.0, "", ha="right", **style)
        # Artists that change every frame: drawn over a cached background (blitting). Every
        # frame is made the same way (background, then these in this order), so the pixels
        # depend on the record only.
        self.dynamic = [
            self.crack_line,
            self.wear_line,
            *self.bars,
            *self.bar_labels,
            *self.rul_stairs.values(),
            *self.rul_interval.values(),
            *self.rul_mean.values(),
            *self.rul_true.values(),
            self.rul_note,
            self.values,
        ]
        for artist in self.dynamic:
            artist.set_animated(True)
        self._layout: tuple | None = None
        self._background: Any = None

    def update(self, record: HealthRecord) -> tuple:
        """Set every artist from ``record`` (no drawing); returns the layout (axis limits,
        static texts) that the background depends on."""
        if not isinstance(record, HealthRecord):
            raise ValueError(f"record must be a HealthRecord, got {type(record).__name__}")
        r = record
        self.crack_line.set_data(r.slots, r.crack_fraction)
        self.wear_line.set_data(r.slots, r.wear_fraction)
        peak = float(max(r.crack_fraction.max(), r.wear_fraction.max()))
        history_x = (float(r.slots[0]), _nice_ceiling(max(float(r.slots[-1]), 10.0)))
        history_y = (0.0, max(1.15, math.ceil(10.0 * 1.05 * peak) / 10.0))
        crack = r.crack_depth_m / r.spring_critical_m
        wear = r.seal_wear_m / r.seal_critical_m
        for bar, value in zip(self.bars, (crack, wear), strict=True):
            bar.set_width(min(value, 1.1))
        self.bar_labels[0].set_text(
            f"{r.crack_depth_m * 1e6:.0f} / {r.spring_critical_m * 1e6:.0f} um"
        )
        self.bar_labels[1].set_text(f"{r.seal_wear_m * 1e6:.2f} / {r.seal_critical_m * 1e6:.2f} um")
        rul_x = self._update_rul(r.rul)
        labels, values = _panel_text(r)
        self.values.set_text(values)
        return (r.title, history_x, history_y, rul_x, labels)

    def _update_rul(self, rul: dict[str, PartRul] | None) -> tuple[float, float]:
        if rul is None:
            for p in PARTS:
                self.rul_stairs[p].set_data(np.zeros(RUL_BINS), np.linspace(0, 1, RUL_BINS + 1))
                self.rul_interval[p].set_data([], [])
                self.rul_mean[p].set_data([], [])
                self.rul_true[p].set_xdata([math.nan, math.nan])
            self.rul_note.set_text("filter RUL not observed in this obs_mode")
            return (0.0, 1.0)
        self.rul_note.set_text("")
        q = {p: d.quantiles((*INTERVAL, 0.99)) for p, d in rul.items()}
        finite_truth = [d.true_flights for d in rul.values() if math.isfinite(d.true_flights)]
        xmax = _nice_ceiling(max([q[p][2] for p in PARTS] + finite_truth + [10.0]))
        edges = np.linspace(0.0, xmax, RUL_BINS + 1)
        for k, p in enumerate(PARTS):
            d = rul[p]
            hist, _ = np.histogram(np.minimum(d.samples_flights, xmax), edges, weights=d.weights)
            self.rul_stairs[p].set_data(hist / max(hist.max(), 1e-300), edges)
            y = 1.1 + 0.12 * k
            self.rul_interval[p].set_data(q[p][:2], [y, y])
            self.rul_mean[p].set_data([d.mean], [y])
            t = d.true_flights if math.isfinite(d.true_flights) else math.nan
            self.rul_true[p].set_xdata([t, t])
        return (0.0, xmax)

    def _draw_background(self, layout: tuple) -> None:
        title, history_x, history_y, rul_x, labels = layout
        self.suptitle.set_text(title or "SCAS actuator health")
        self.ax_history.set_xlim(*history_x)
        self.ax_history.set_ylim(*history_y)
        self.ax_rul.set_xlim(*rul_x)
        self.labels.set_text(labels)
        canvas = self.figure.canvas
        canvas.draw()
        self._background = canvas.copy_from_bbox(self.figure.bbox)
        self._layout = layout

    def draw(self, record: HealthRecord) -> np.ndarray:
        """The frame of ``record``: ``(H, W, 3)`` uint8 RGB."""
        layout = self.update(record)
        if layout != self._layout:
            self._draw_background(layout)
        canvas = self.figure.canvas
        canvas.restore_region(self._background)
        for artist in self.dynamic:
            artist.axes.draw_artist(artist)
        return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()

    def show(self, record: HealthRecord, pause_s: float = 1e-3) -> None:
        """Draw ``record`` on screen (``interactive=True``: pyplot's window)."""
        if not self.interactive:
            raise RuntimeError("show() needs HealthDashboard(interactive=True)")
        import matplotlib.pyplot as plt

        self.draw(record)
        self.figure.canvas.blit(self.figure.bbox)
        plt.pause(pause_s)

    def close(self) -> None:
        if self.interactive:
            import matplotlib.pyplot as plt

            plt.close(self.figure)
        self.figure.clear()


def _nice_ceiling(x: float) -> float:
    """Smallest of 1, 2, 2.5, 5 times a power of ten that is >= ``x`` (axis limits that do
    not jitter from frame to frame)."""
    power = 10.0 ** math.floor(math.log10(x))
    for m in (1.0, 2.0, 2.5, 5.0, 10.0):
        if m * power >= x:
            return m * power
    return 10.0 * power  # pragma: no cover


def _panel_text(r: HealthRecord) -> tuple[str, str]:
    """(labels, values) of the text panel: two columns, labels left, values right."""
    rows = [("latest features", "")]
    rows += [(f"  {name} ({unit})", f"{value:.4g}") for name, value, unit in r.features]
    rows += [
        ("", ""),
        ("slot", f"{int(r.slots[-1])}"),
        ("availability", f"{r.availability:.3f}"),
        ("flights / tests", f"{r.flights} / {r.tests}"),
        ("cost (kUSD)", f"{r.cost_usd / 1e3:.1f}"),
        ("revenue (kUSD)", f"{r.revenue_usd / 1e3:.1f}"),
        ("failures sp/se", f"{r.failures['spring']} / {r.failures['seal']}"),
        ("replaced sp/se", f"{r.replacements['spring']} / {r.replacements['seal']}"),
        ("downtime (slots)", f"{r.downtime}"),
    ]
    return "\n".join(a for a, _ in rows), "\n".join(b for _, b in rows)


# ---------------------------------------------------------------------------- env glue
class DashboardRenderer:
    """What an env holds for ``render_mode`` ``"rgb_array"`` or ``"human"``.

    Call :meth:`observe` at the end of ``reset()`` and ``step()`` and :meth:`render` in
    ``render()``: a frame (``"rgb_array"``) or a window update (``"human"``, returns None).
    """

    MODES = ("rgb_array", "human")

    def __init__(self, render_mode: str) -> None:
        if render_mode not in self.MODES:
            raise ValueError(f"render_mode = {render_mode!r} must be one of {self.MODES}")
        self.render_mode = render_mode
        self.trace = HealthTrace()
        self._dashboard: HealthDashboard | None = None

    @property
    def dashboard(self) -> HealthDashboard:
        if self._dashboard is None:  # the figure is built on the first frame
            self._dashboard = HealthDashboard(interactive=self.render_mode == "human")
        return self._dashboard

    def __getstate__(self) -> dict[str, Any]:
        """Pickles (and deep copies) without the figure; it is rebuilt on the next frame."""
        state = dict(self.__dict__)
        state["_dashboard"] = None
        return state

    def observe(self, env: Any) -> None:
        """Record the env's state (call at the end of ``reset()`` and of ``step()``)."""
        self.trace.record(env)

    def render(self, env: Any) -> np.ndarray | None:
        record = frame_record_from_env(env, self.trace)
        if self.render_mode == "human":
            self.dashboard.show(record)
            return None
        return self.dashboard.draw(record)

    def close(self) -> None:
        if self._dashboard is not None:
            self._dashboard.close()
            self._dashboard = None


__all__ = [
    "DashboardRenderer",
    "HealthDashboard",
    "HealthRecord",
    "HealthTrace",
    "PartRul",
    "critical_levels",
    "episode_totals",
    "frame_record_from_env",
    "latest_features",
    "rul_distribution",
    "true_state",
    "unit_growth_multipliers",
]
