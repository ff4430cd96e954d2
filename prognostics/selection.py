"""Feature selection: KL redundancy, correlation, SNR, accuracy, severity at detection.

Implements [DJS20] §4 with the procedure of the reference sheet §7.2. The input is a feature
table for one fault mode and one operating condition: ``severity`` (R,) per run (0 =
healthy; normalised to the critical level or discrete level values, at least two healthy
runs and one faulty level) and ``features``, a mapping name -> (R,) values on the same runs.

Detection-based metrics use the :class:`~prognostics.detection.PercentileDetector` rule so
that they agree with online detection: the detector is fitted on the healthy runs, with the
direction inferred from the data (see :func:`score_feature`).

>>> rng = np.random.default_rng(0)
>>> sev = np.repeat(np.linspace(0.0, 1.0, 8), 100)
>>> table = {"good": sev + 0.1 * rng.standard_normal(sev.size),
...          "noise": rng.standard_normal(sev.size)}
>>> [s.name for s in rank_features(table, sev)]
['good', 'noise']
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np
import scipy.stats
from numpy.typing import ArrayLike, NDArray

from prognostics import validation as check
from prognostics.detection import DetectorConfig, PercentileDetector

if TYPE_CHECKING:  # matplotlib is imported lazily, inside the plotting function
    from matplotlib.figure import Figure

__all__ = [
    "DEFAULT_REDUNDANCY_NATS",
    "FeatureScore",
    "RedundantPair",
    "gaussian_jeffreys",
    "histogram_jeffreys",
    "normalised_response",
    "plot_accuracy_sensitivity",
    "rank_features",
    "redundancy_matrix",
    "redundant_pairs",
    "score_feature",
]

FloatArray = NDArray[np.float64]
Method = Literal["gaussian", "histogram"]

DEFAULT_REDUNDANCY_NATS = 0.1
"""Jeffreys divergence below which two candidates are redundant (reference sheet §7.2)."""

#: Most histogram bins :func:`histogram_jeffreys` accepts (a count; far above any useful one)
MAX_BINS = 1_000_000
#: ``numpy.histogram_bin_edges`` rules :func:`histogram_jeffreys` accepts by name
BIN_RULES: tuple[str, ...] = ("auto", "fd", "doane", "scott", "stone", "rice", "sturges", "sqrt")
METHODS: tuple[str, ...] = ("gaussian", "histogram")


# ----------------------------------------------------------------------------- validation
def _severity(severity: ArrayLike) -> FloatArray:
    sev = check.array("severity", severity, ndim=1, ge=0.0)
    if np.count_nonzero(sev == 0.0) < 2 or not np.any(sev > 0.0):
        raise ValueError(
            "severity must hold at least 2 healthy runs (severity 0) and one faulty run, got "
            f"{np.count_nonzero(sev == 0.0)} healthy of {sev.size}"
        )
    return sev


def _values(label: str, values: ArrayLike, sev: FloatArray) -> FloatArray:
    """One candidate's values (``label`` names the argument): finite, one per run, not
    constant over the healthy runs."""
    arr = check.array(label, values, shape=sev.shape, like="severity")
    if np.std(arr[sev == 0.0]) == 0.0:
        raise ValueError(f"{label} is constant over the healthy runs: no noise scale")
    return arr


def _table(
    features: Mapping[str, ArrayLike], severity: ArrayLike
) -> tuple[list[str], FloatArray, FloatArray]:
    check.mapping("features", features)
    sev = _severity(severity)
    if len(features) < 1:
        raise ValueError("features must contain at least one candidate")
    names = list(features)
    for name in names:
        if not isinstance(name, str):
            raise check.ArgumentTypeError(
                f"features has the key {check.show(name)}: feature names must be strings"
            )
    return names, np.stack([_values(f"features[{n!r}]", features[n], sev) for n in names]), sev


def _shift_sign(values: FloatArray, sev: FloatArray) -> float:
    """+1 if the mean at the highest severity is >= the healthy mean, else -1."""
    shift = np.mean(values[sev == sev.max()]) - np.mean(values[sev == 0.0])
    return 1.0 if shift >= 0.0 else -1.0


# ----------------------------------------------------------------------------- redundancy
def normalised_response(values: ArrayLike, severity: ArrayLike) -> FloatArray:
    """Feature z-scored with its healthy mean and std (ddof=1), oriented to rise with severity.

    z = s (f - mean_h(f)) / std_h(f), s = sign(mean_{s_max}(f) - mean_h(f)), so features
    with the same response up to an affine map (e.g. I5 = c I6) get identical z.
    """
    sev = _severity(severity)
    arr = _values("values", values, sev)
    healthy = arr[sev == 0.0]
    z = (arr - healthy.mean()) / healthy.std(ddof=1)
    return _shift_sign(arr, sev) * z


def gaussian_jeffreys(p_samples: ArrayLike, q_samples: ArrayLike) -> float:
    """Symmetric KL (Jeffreys) divergence of Gaussian fits to two samples (nats).

    With P = N(mu_p, s_p^2), Q = N(mu_q, s_q^2) (sample mean and ddof=1 std), from
    D(P||Q) = ln(s_q/s_p) + (s_p^2 + (mu_p - mu_q)^2)/(2 s_q^2) - 1/2 (reference §7.2):

        J = D(P||Q) + D(Q||P) = (s_p^2 - s_q^2)^2 / (2 s_p^2 s_q^2)
                                + (mu_p - mu_q)^2 (1/s_p^2 + 1/s_q^2) / 2.

    >>> round(gaussian_jeffreys([-1.0, 1.0], [0.0, 2.0]), 6)  # shift 1, var 2 each: 1/2
    0.5
    """
    p = _sample("p_samples", p_samples)
    q = _sample("q_samples", q_samples)
    var_p, var_q = p.var(ddof=1), q.var(ddof=1)
    if var_p == 0.0 or var_q == 0.0:
        raise ValueError("p_samples and q_samples must not be constant (zero variance)")
    d_mu2 = (p.mean() - q.mean()) ** 2
    return float(
        (var_p - var_q) ** 2 / (2.0 * var_p * var_q) + 0.5 * d_mu2 * (1 / var_p + 1 / var_q)
    )


def histogram_jeffreys(
    p_samples: ArrayLike,
    q_samples: ArrayLike,
    *,
    bins: int | str = "fd",
    pseudo_count: float = 0.5,
) -> float:
    """Symmetric KL (Jeffreys) divergence from histograms of two samples (nats).

    Both samples are binned on common edges ``numpy.histogram_bin_edges`` of the pooled
    data (``bins``: a count or a numpy rule, default Freedman-Diaconis); each bin gets
    ``pseudo_count`` extra counts (0.5 = Krichevsky-Trofimov) so that empty bins keep the
    divergence finite; J = entropy(p, q) + entropy(q, p) with ``scipy.stats.entropy``
    (natural log). Its bias is about (bins - 1)/n per direction for n samples.
    """
    p = _sample("p_samples", p_samples)
    q = _sample("q_samples", q_samples)
    if isinstance(bins, str):
        check.choice("bins", bins, BIN_RULES)
    else:
        check.integer("bins", bins, ge=1, le=MAX_BINS)
    check.real("pseudo_count", pseudo_count, gt=0.0)
    edges = np.histogram_bin_edges(np.concatenate([p, q]), bins=bins)
    pk = np.histogram(p, bins=edges)[0] + pseudo_count
    qk = np.histogram(q, bins=edges)[0] + pseudo_count
    return float(scipy.stats.entropy(pk, qk) + scipy.stats.entropy(qk, pk))


def _sample(name: str, values: ArrayLike) -> FloatArray:
    return check.array(name, values, ndim=1, min_size=2)


def _jeffreys(method: Method) -> Callable[[ArrayLike, ArrayLike], float]:
    if check.choice("method", method, METHODS) == "gaussian":
        return gaussian_jeffreys
    return histogram_jeffreys


def redundancy_matrix(
    features: Mapping[str, ArrayLike], severity: ArrayLike, *, method: Method = "gaussian"
) -> tuple[list[str], FloatArray]:
    """Pairwise Jeffreys divergence of the normalised responses, pooled over severities.

    Each candidate is mapped by :func:`normalised_response`; the divergence between the
    distributions of z over all runs is computed by :func:`gaussian_jeffreys` or
    :func:`histogram_jeffreys`. Small values mean the two features respond alike to the
    fault (redundant). Being a comparison of marginals, it also calls two features that do
    not respond at all "redundant"; such candidates fail the ranking metrics anyway.

    Returns the names and the symmetric (F, F) matrix (nats, zero diagonal).
    """
    jeffreys = _jeffreys(method)
    names, table, sev = _table(features, severity)
    z = [normalised_response(row, sev) for row in table]
    matrix = np.zeros((len(names), len(names)))
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            matrix[a, b] = matrix[b, a] = jeffreys(z[a], z[b])
    return names, matrix


@dataclass(frozen=True)
class RedundantPair:
    """Two redundant candidates, their divergence (nats) and the one to drop."""

    first: str
    second: str
    divergence_nats: float
    drop: str


def redundant_pairs(
    features: Mapping[str, ArrayLike],
    severity: ArrayLike,
    complexity: Mapping[str, float],
    *,
    threshold_nats: float = DEFAULT_REDUNDANCY_NATS,
    method: Method = "gaussian",
) -> list[RedundantPair]:
    """Pairs with divergence below ``threshold_nats`` and which member to drop.

    The dropped member is the more complex one (higher ``complexity`` rank, e.g.
    ``FEATURE_INFO[id].complexity``), as [DJS20] dropped I5 against I6; on equal complexity
    the one with the lower |Spearman| correlation with severity, then the later name.
    """
    check.real("threshold_nats", threshold_nats, gt=0.0)
    check.mapping("complexity", complexity)
    _jeffreys(method)
    names, _, _ = _table(features, severity)
    missing = [n for n in names if n not in complexity]
    if missing:
        raise ValueError(f"complexity has no rank for features {missing}")
    for n in names:
        check.real(f"complexity[{n!r}]", complexity[n])
    names, matrix = redundancy_matrix(features, severity, method=method)
    sev = _severity(severity)
    pairs = []
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            if matrix[a, b] < threshold_nats:
                key_a = _drop_key(names[a], features, sev, complexity)
                key_b = _drop_key(names[b], features, sev, complexity)
                drop = names[a] if key_a > key_b else names[b]
                pairs.append(RedundantPair(names[a], names[b], float(matrix[a, b]), drop))
    return pairs


def _drop_key(
    name: str, features: Mapping[str, ArrayLike], sev: FloatArray, complexity: Mapping[str, float]
) -> tuple[float, float, str]:
    """Larger key = dropped first: complexity, then weaker |Spearman|, then later name."""
    rho = scipy.stats.spearmanr(np.asarray(features[name], dtype=np.float64), sev).statistic
    return (float(complexity[name]), -abs(float(rho)), name)


# ----------------------------------------------------------------------------- metrics
@dataclass(frozen=True)
class FeatureScore:
    """Selection metrics of one candidate (see :func:`score_feature`)."""

    name: str
    direction: Literal["rising", "falling"]
    pearson: float
    spearman: float
    snr_db: float
    accuracy: float
    severity_at_detection: float
    max_severity: float
    score: float


def score_feature(
    name: str,
    values: ArrayLike,
    severity: ArrayLike,
    *,
    config: DetectorConfig | None = None,
) -> FeatureScore:
    """Correlation, SNR, accuracy and severity at detection of one candidate.

    - direction: "rising" if mean_{s_max}(f) >= mean_0(f), else "falling";
    - pearson, spearman: correlation of f with severity over all runs (scipy.stats);
    - SNR_dB = 10 log10((mean_{s_max}(f) - mean_0(f))^2 / std_0(f)^2), std with ddof=1
      (reference §7.2; -inf if the means are equal);
    - detector: ``config`` (default :class:`DetectorConfig`) with the inferred direction,
      fitted on the healthy runs (its ``window`` is not used: each severity level's runs
      form one window);
    - accuracy (probability of correct response): mean over severity levels of the share
      of runs classified correctly, a run being "faulty" when it lies beyond the baseline
      threshold (:meth:`PercentileDetector.exceeds`); healthy runs are correct when not;
    - severity at detection: lowest faulty level from which every level up to s_max
      alarms when all its runs form the running window
      (:meth:`PercentileDetector.window_alarm`, i.e. the share ``fraction`` of the level's
      distribution lies beyond the baseline percentile, as in §5.1); NaN if s_max does
      not alarm;
    - score = accuracy * |spearman| * (1 - severity_at_detection / s_max), 0 if not
      detected: high for accurate, monotone features that alarm early.
    """
    if not isinstance(name, str):
        raise check.ArgumentTypeError(f"name = {check.show(name)} must be a string")
    if config is not None:
        check.instance("config", config, DetectorConfig)
    sev = _severity(severity)
    arr = _values("values", values, sev)
    healthy = arr[sev == 0.0]
    s_max = float(sev.max())
    shift = float(np.mean(arr[sev == s_max]) - healthy.mean())
    direction: Literal["rising", "falling"] = "rising" if shift >= 0.0 else "falling"
    snr_db = 10.0 * np.log10(shift**2 / healthy.var(ddof=1)) if shift != 0.0 else -np.inf

    base_config = DetectorConfig() if config is None else config
    detector = PercentileDetector(dataclasses.replace(base_config, direction=direction))
    detector.fit(healthy)
    levels = np.unique(sev)
    correct = [np.mean(detector.exceeds(arr[sev == lv]) == (lv > 0.0)) for lv in levels]
    alarmed = [detector.window_alarm(arr[sev == lv]) for lv in levels[1:]]
    s_det = float("nan")
    for lv, alarm in zip(levels[:0:-1], alarmed[::-1], strict=True):
        if not alarm:
            break
        s_det = float(lv)
    accuracy = float(np.mean(correct))
    spearman = float(scipy.stats.spearmanr(arr, sev).statistic)
    earliness = 0.0 if np.isnan(s_det) else 1.0 - s_det / s_max
    return FeatureScore(
        name=name,
        direction=direction,
        pearson=float(scipy.stats.pearsonr(arr, sev).statistic),
        spearman=spearman,
        snr_db=float(snr_db),
        accuracy=accuracy,
        severity_at_detection=s_det,
        max_severity=s_max,
        score=accuracy * abs(spearman) * earliness,
    )


def rank_features(
    features: Mapping[str, ArrayLike],
    severity: ArrayLike,
    *,
    config: DetectorConfig | None = None,
) -> list[FeatureScore]:
    """:func:`score_feature` for every candidate, best first (score, then SNR_dB)."""
    if config is not None:
        check.instance("config", config, DetectorConfig)
    names, table, sev = _table(features, severity)
    scores = [
        score_feature(n, row, sev, config=config) for n, row in zip(names, table, strict=True)
    ]
    return sorted(scores, key=lambda s: (s.score, s.snr_db), reverse=True)


# ----------------------------------------------------------------------------- plot
def plot_accuracy_sensitivity(
    scores: Sequence[FeatureScore],
    path: str | os.PathLike[str],
    *,
    title: str | None = None,
    xlabel: str = "severity at detection",
) -> Figure:
    """Accuracy-sensitivity plane of [DJS20] Fig. 8, saved to ``path`` (format from suffix).

    x = severity at detection (axis labelled ``xlabel``), y = accuracy, bubble area linear
    in SNR_dB (lowest -> 40 pt^2, highest -> 900 pt^2), labelled with the feature name.
    Undetected candidates are drawn hollow at x = s_max with "(n.d.)". Uses the Agg canvas
    directly (no pyplot state).
    """
    check.sequence("scores", scores)
    if len(scores) == 0:
        raise ValueError("scores must contain at least one FeatureScore")
    for k, s in enumerate(scores):
        check.instance(f"scores[{k}]", s, FeatureScore)
    if not isinstance(path, str | os.PathLike):
        raise check.ArgumentTypeError(f"path = {check.show(path)} must be a str or a path")
    if title is not None and not isinstance(title, str):
        raise check.ArgumentTypeError(f"title = {check.show(title)} must be a string or None")
    if not isinstance(xlabel, str):
        raise check.ArgumentTypeError(f"xlabel = {check.show(xlabel)} must be a string")
    out = Path(path)
    if not out.parent.is_dir():
        raise ValueError(f"path's directory {out.parent} does not exist")
    snr = np.array([s.snr_db for s in scores])
    finite = snr[np.isfinite(snr)]
    lo, hi = (finite.min(), finite.max()) if finite.size else (0.0, 0.0)
    span = hi - lo if hi > lo else 1.0
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.8))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for s, level in zip(scores, snr, strict=True):
        area = 40.0 + 860.0 * ((level - lo) / span if np.isfinite(level) else 0.0)
        detected = not np.isnan(s.severity_at_detection)
        x_pos = s.severity_at_detection if detected else s.max_severity
        ax.scatter(
            x_pos,
            s.accuracy,
            s=area,
            alpha=0.6,
            facecolors="tab:blue" if detected else "none",
            edgecolors="tab:blue",
        )
        label = s.name if detected else f"{s.name} (n.d.)"
        ax.annotate(label, (x_pos, s.accuracy), textcoords="offset points", xytext=(6, 6))
    ax.set_xlabel(xlabel)
    ax.set_ylabel("accuracy (probability of correct response)")
    ax.set_ylim(0.0, 1.05)
    ax.set_title(title if title is not None else "Feature selection (bubble area ~ SNR dB)")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    return fig
