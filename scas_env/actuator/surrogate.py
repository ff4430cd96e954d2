"""Surrogate of the measured features: a random-effects model calibrated on physics runs.

For each feature ``f`` the surrogate draws, at crack fraction ``c = a / a_crit`` and seal
wear fraction ``w = lambda / lambda_crit``::

    f = mu_f(c, w) + tau_f(c, w) z_unit + sigma_f(c, w) z_run,     z ~ N(0, 1)

* ``mu``: mean over units and runs; ``tau``: between-installation spread (spring geometry
  tolerances and any valve null bias: fixed for an installation, so ``z_unit`` is drawn once
  when a spring pair is fitted and kept until it is replaced); ``sigma``: run-to-run spread
  (fluid temperature, air, supply pressure, sensor noise, the flight's command draw).
* All three are tabulated on a grid of (c, w) and interpolated bilinearly; outside
  [0, 1]^2 a ``ValueError`` is raised (a part at its critical value has failed).
* The tables come from a nested physics design (``experiments.build.surrogate``): at every
  grid point, several units with several runs each; ``tau`` and ``sigma`` from the one-way
  random-effects ANOVA (``tau^2 = (MS_between - MS_within)/R``, taken as 0 when the
  estimate is negative, the usual truncated estimator).

Features are independent given (c, w, z_unit); cross-feature correlations inside a run
are not modelled (documented simplification; the test against fresh physics checks means
and spreads only).

    >>> model = default_surrogate()
    >>> model.features
    ('G3', 'G1', 'I2', 'I6', 'I7', 'I8', 'I9')
    >>> bool(model.mean_at(0.0, 1.0)[0] > model.mean_at(0.0, 0.0)[0])  # G3 rises with wear
    True
"""

from __future__ import annotations

import json
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from scas_env.utils.atomic_file import refuse_existing, write_text_atomic
from scas_env.utils.shipped_files import shipped_path, verify_shipped_file
from scas_env.utils.table_checks import finite_array, load_json_table, whole_number

FloatArray = npt.NDArray[np.float64]
SURROGATE_VERSION = 1
DATA_FILE = "surrogate.json"
#: Features the surrogate models and the condition each is measured in.
FEATURE_CONDITION = {
    "G3": "ground",
    "G1": "ground",
    "I2": "flight",
    "I6": "flight",
    "I7": "flight",
    "I8": "flight",
    "I9": "flight",
}


@dataclass(frozen=True, eq=False)
class SurrogateModel:
    """Tabulated random-effects model of the features (see the module docstring).

    Attributes
    ----------
    features : feature ids, in the order of the first axis of the tables.
    crack_grid, wear_grid : grid of crack and wear fractions of critical, ascending, [0, 1].
    mean, unit_std, run_std : tables of shape (features, crack, wear), feature units.
    params_digest : digest of the parameters the physics ran with.
    seed, units_per_point, runs_per_unit : the design it was built from.
    feature_designs : features whose tables come from another design, with that design
        (``experiments.build.surrogate``: I8 and I9 from a paired design).
    """

    features: tuple[str, ...]
    crack_grid: FloatArray
    wear_grid: FloatArray
    mean: FloatArray
    unit_std: FloatArray
    run_std: FloatArray
    params_digest: str
    seed: int
    units_per_point: int
    runs_per_unit: int
    version: int = SURROGATE_VERSION
    feature_designs: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        own = "SurrogateModel"
        if not isinstance(self.version, int) or self.version != SURROGATE_VERSION:
            raise ValueError(
                f"surrogate version {self.version!r} is not the supported {SURROGATE_VERSION}; "
                "rebuild it with python -m experiments.build.surrogate (a source checkout)"
            )
        if isinstance(self.features, str) or not all(isinstance(f, str) for f in self.features):
            raise ValueError(f"{own}.features = {self.features!r} must be a list of feature ids")
        features = tuple(self.features)
        if not features or len(set(features)) != len(features):
            raise ValueError(f"{own}.features = {features!r} must be non-empty, without repeats")
        object.__setattr__(self, "features", features)
        designs = self.feature_designs
        if (
            not isinstance(designs, dict)
            or not all(isinstance(v, str) for v in designs.values())
            or not set(designs) <= set(features)
        ):
            raise ValueError(
                f"{own}.feature_designs = {designs!r} must map modelled features {features} "
                "to design descriptions (strings)"
            )
        object.__setattr__(self, "feature_designs", dict(designs))
        if not isinstance(self.params_digest, str):
            raise ValueError(f"{own}.params_digest = {self.params_digest!r} must be a string")
        for name, lo in (("seed", 0), ("units_per_point", 1), ("runs_per_unit", 1)):
            object.__setattr__(self, name, whole_number(own, name, getattr(self, name), lo=lo))
        for name in ("crack_grid", "wear_grid"):
            grid = finite_array(own, name, getattr(self, name), ndim=1, min_size=2, increasing=True)
            if grid[0] != 0.0 or grid[-1] != 1.0:
                raise ValueError(
                    f"{own}.{name} runs from {float(grid[0])!r} to {float(grid[-1])!r}; "
                    "it must rise strictly from 0 to 1 (fractions of critical)"
                )
            object.__setattr__(self, name, grid)
        shape = (len(features), self.crack_grid.size, self.wear_grid.size)
        lows = {"mean": (None, False), "unit_std": (0.0, False), "run_std": (0.0, True)}
        for name, (lo, lo_open) in lows.items():
            arr = finite_array(own, name, getattr(self, name), ndim=3, lo=lo, lo_open=lo_open)
            if arr.shape != shape:
                raise ValueError(
                    f"{own}.{name} has shape {arr.shape}; it must have shape {shape} "
                    "(features, crack grid, wear grid)"
                )
            object.__setattr__(self, name, arr)
        stack = np.stack([self.mean, self.unit_std, self.run_std])
        stack.setflags(write=False)
        object.__setattr__(self, "_stack", stack)
        object.__setattr__(self, "_crack_list", self.crack_grid.tolist())
        object.__setattr__(self, "_wear_list", self.wear_grid.tolist())
        object.__setattr__(self, "_stack_lists", stack.tolist())

    def with_features_from(
        self, other: SurrogateModel, features: Sequence[str], design: str
    ) -> SurrogateModel:
        """This model with the tables of ``features`` taken from ``other`` (same features,
        grids and parameters), recorded in :attr:`feature_designs` as ``design``."""
        if (
            other.features != self.features
            or not np.array_equal(other.crack_grid, self.crack_grid)
            or not np.array_equal(other.wear_grid, self.wear_grid)
            or other.params_digest != self.params_digest
        ):
            raise ValueError(
                "with_features_from: the other model must have the same features, grids and "
                f"parameters (features {other.features} vs {self.features}, params "
                f"{other.params_digest} vs {self.params_digest})"
            )
        rows = [self.index(f) for f in features]
        tables = {}
        for name in ("mean", "unit_std", "run_std"):
            table = np.array(getattr(self, name))
            table[rows] = getattr(other, name)[rows]
            tables[name] = table
        designs = self.feature_designs | dict.fromkeys(features, design)
        return replace(self, **tables, feature_designs=designs)

    def index(self, feature: str) -> int:
        """Position of ``feature`` in :attr:`features`."""
        if feature not in self.features:
            raise ValueError(f"feature {feature!r} is not modelled; available: {self.features}")
        return self.features.index(feature)

    def _weights(
        self, crack_frac: npt.ArrayLike, wear_frac: npt.ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        c = np.asarray(crack_frac, dtype=np.float64)
        w = np.asarray(wear_frac, dtype=np.float64)
        for name, v in (("crack_frac", c), ("wear_frac", w)):
            if not np.all(np.isfinite(v)) or np.any(v < 0.0) or np.any(v > 1.0):
                raise ValueError(f"{name} = {v} must lie in [0, 1] (fraction of critical)")
        i = np.clip(
            np.searchsorted(self.crack_grid, c, side="right") - 1, 0, self.crack_grid.size - 2
        )
        j = np.clip(
            np.searchsorted(self.wear_grid, w, side="right") - 1, 0, self.wear_grid.size - 2
        )
        tc = (c - self.crack_grid[i]) / (self.crack_grid[i + 1] - self.crack_grid[i])
        tw = (w - self.wear_grid[j]) / (self.wear_grid[j + 1] - self.wear_grid[j])
        return i, j, tc, tw

    def _interp(self, table: FloatArray, crack_frac: npt.ArrayLike, wear_frac: npt.ArrayLike):
        i, j, tc, tw = self._weights(crack_frac, wear_frac)
        return (
            table[:, i, j] * (1 - tc) * (1 - tw)
            + table[:, i + 1, j] * tc * (1 - tw)
            + table[:, i, j + 1] * (1 - tc) * tw
            + table[:, i + 1, j + 1] * tc * tw
        )

    def mean_at(self, crack_frac: npt.ArrayLike, wear_frac: npt.ArrayLike) -> FloatArray:
        """Mean of every feature at (c, w): shape (features, *broadcast shape)."""
        return self._interp(self.mean, crack_frac, wear_frac)

    def unit_std_at(self, crack_frac: npt.ArrayLike, wear_frac: npt.ArrayLike) -> FloatArray:
        """Between-installation standard deviation at (c, w)."""
        return self._interp(self.unit_std, crack_frac, wear_frac)

    def run_std_at(self, crack_frac: npt.ArrayLike, wear_frac: npt.ArrayLike) -> FloatArray:
        """Run-to-run standard deviation at (c, w)."""
        return self._interp(self.run_std, crack_frac, wear_frac)

    def _cell(self, crack_frac: float, wear_frac: float) -> tuple[int, int, float, float]:
        """Grid cell (i, j) holding one scalar (c, w) and the fractions (tc, tw) inside it."""
        c, w = float(crack_frac), float(wear_frac)
        if not (0.0 <= c <= 1.0 and 0.0 <= w <= 1.0):
            raise ValueError(f"crack_frac = {c} and wear_frac = {w} must lie in [0, 1]")
        cg, wg = self._crack_list, self._wear_list
        i = min(bisect_right(cg, c) - 1, len(cg) - 2)
        j = min(bisect_right(wg, w) - 1, len(wg) - 2)
        tc = (c - cg[i]) / (cg[i + 1] - cg[i])
        tw = (w - wg[j]) / (wg[j + 1] - wg[j])
        return i, j, tc, tw

    def tables_at(self, crack_frac: float, wear_frac: float) -> FloatArray:
        """(mean, unit_std, run_std) of every feature at one scalar (c, w): shape (3, F).

        The scalar fast path of :meth:`mean_at` and friends (same bilinear values).
        """
        i, j, tc, tw = self._cell(crack_frac, wear_frac)
        corner = self._stack[:, :, i : i + 2, j : j + 2]
        return (
            corner[:, :, 0, 0] * ((1 - tc) * (1 - tw))
            + corner[:, :, 1, 0] * (tc * (1 - tw))
            + corner[:, :, 0, 1] * ((1 - tc) * tw)
            + corner[:, :, 1, 1] * (tc * tw)
        )

    def feature_mean(self, k: int, crack_frac: float, wear_frac: float) -> float:
        """Mean of feature ``k`` at one scalar (c, w): ``tables_at(c, w)[0, k]``, the same
        float, without the arrays (the monitor's per-test path)."""
        return self._scalar_tables(crack_frac, wear_frac, (k,), (0,))[0]

    def _scalar_tables(
        self, crack_frac: float, wear_frac: float, idx: Sequence[int], stats: Sequence[int]
    ) -> list[float]:
        """``tables_at(c, w)[s, k]`` for s in ``stats``, k in ``idx`` (that order), as Python
        floats with the same arithmetic: the bilinear weights of :meth:`tables_at`."""
        i, j, tc, tw = self._cell(crack_frac, wear_frac)
        w00, w10 = (1 - tc) * (1 - tw), tc * (1 - tw)
        w01, w11 = (1 - tc) * tw, tc * tw
        out = []
        for s in stats:
            table = self._stack_lists[s]
            for k in idx:
                lo, hi = table[k][i], table[k][i + 1]
                out.append(lo[j] * w00 + hi[j] * w10 + lo[j + 1] * w01 + hi[j + 1] * w11)
        return out

    def sample(
        self,
        crack_frac: float,
        wear_frac: float,
        unit_z: FloatArray,
        rng: np.random.Generator,
        idx: list[int],
    ) -> FloatArray:
        """One run's features ``idx`` at (c, w) for an installation with effects ``unit_z``.

        ``unit_z`` holds one standard-normal draw per modelled feature (from
        :meth:`draw_unit_z`, ``len(features)`` values); the run noise is
        ``rng.standard_normal(len(idx))``. Each index must lie in ``0 <= k < len(features)``
        (a negative one is refused, not counted from the end). ``ValueError`` otherwise,
        before any draw.
        """
        return np.array(self.sample_list(crack_frac, wear_frac, unit_z, rng, idx))

    def sample_list(
        self,
        crack_frac: float,
        wear_frac: float,
        unit_z: FloatArray,
        rng: np.random.Generator,
        idx: Sequence[int],
    ) -> list[float]:
        """:meth:`sample` as a list of Python floats (the same values, without arrays);
        the same checks of ``unit_z`` and ``idx``."""
        nf = len(self.features)
        if len(unit_z) != nf:
            raise ValueError(
                f"unit_z has {len(unit_z)} values; one per modelled feature ({nf}) is required"
            )
        if len(idx) and not (min(idx) >= 0 and max(idx) < nf):  # cheap: no per-k loop
            bad = next(k for k in idx if not 0 <= k < nf)
            raise ValueError(f"idx holds feature index {bad!r}; allowed: 0 <= k < {nf}")
        n = len(idx)
        t = self._scalar_tables(crack_frac, wear_frac, idx, (0, 1, 2))
        z = rng.standard_normal(n).tolist()
        return [t[m] + t[n + m] * float(unit_z[k]) + t[2 * n + m] * z[m] for m, k in enumerate(idx)]

    def draw_unit_z(self, rng: np.random.Generator, n_drawn: int | None = None) -> FloatArray:
        """Standardised installation effects, one per modelled feature.

        ``n_drawn``: draw the effects of the first ``n_drawn`` features only (the others are
        0), so that a user of the first features draws as many normals as before later
        features were added to the surrogate. Default: all.
        """
        n = len(self.features)
        if n_drawn is None:
            return rng.standard_normal(n)
        if not 1 <= n_drawn <= n:
            raise ValueError(f"n_drawn = {n_drawn!r} must lie in [1, {n}] (modelled features)")
        z = np.zeros(n)
        z[:n_drawn] = rng.standard_normal(n_drawn)
        return z

    def to_dict(self) -> dict:
        out = asdict(self)
        for key, value in out.items():
            if isinstance(value, np.ndarray):
                out[key] = value.tolist()
        out["features"] = list(self.features)
        return out

    def save(self, path: str | Path, *, overwrite: bool = False) -> None:
        """Write the table as JSON, atomically; an existing file raises ``FileExistsError``
        unless ``overwrite``."""
        refuse_existing(path, overwrite)
        write_text_atomic(path, json.dumps(self.to_dict()) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> SurrogateModel:
        """Read a surrogate file; every error names the file, and a shipped file is checked
        against the SHA-256 manifest (:mod:`scas_env.utils.shipped_files`)."""
        verify_shipped_file(path)
        return load_json_table(path, lambda data: cls(**data), "surrogate")


@lru_cache(maxsize=1)
def default_surrogate() -> SurrogateModel:
    """The shipped surrogate of the default :class:`~scas_env.actuator.params.ScasParams`."""
    return SurrogateModel.load(shipped_path(DATA_FILE))


#: ScasParams fields the features do not depend on (the surrogate tabulates them on the
#: crack and wear fractions): the growth and wear constants, their unit scatter, the flaw
#: a part starts from and a flight's length
DEGRADATION_ONLY: dict[str, tuple[str, ...]] = {
    "spring": (
        "paris_c", "paris_m", "delta_k_threshold_mpa_sqrt_m", "walker_gamma", "initial_crack_m",
    ),
    "seal": ("wear_rate_m3_n_m", "friction_coefficient", "contact_width_m"),  # Archard's law
    "uncertainty": ("paris_c_log_sigma", "wear_rate_log_sigma", "initial_crack_sigma_m"),
    "mission": ("flight_duration_s",),
}  # fmt: skip


def shipped_surrogate_for(params: Any) -> SurrogateModel:
    """The shipped surrogate, for ``params`` (a ``ScasParams``) that differ from the defaults
    in :data:`DEGRADATION_ONLY` fields at most; otherwise a ``ValueError`` naming the fields
    the features depend on (the sensing, the design, the fluid...), since the shipped
    tables would give the default's features, detector thresholds and go/no-go limits."""
    from scas_env.actuator.params import ScasParams

    ours, default = params.to_dict(), ScasParams().to_dict()
    changed = [
        f"{group}.{name}"
        for group, fields in ours.items()
        for name, value in fields.items()
        if value != default[group][name] and name not in DEGRADATION_ONLY.get(group, ())
    ]
    if changed:
        raise ValueError(
            f"params differ from the defaults in {changed}, which the features depend on; the "
            "shipped feature surrogate is the default params'. Pass surrogate= a SurrogateModel "
            "built for these params (python -m experiments.build.surrogate --params FILE), or "
            "surrogate=default_surrogate() to keep the default's features knowingly"
        )
    return default_surrogate()
