"""The episode state of N actuators as arrays: what the observation and the info are made of.

One :class:`FleetState` row is everything an observation or an ``info`` of one actuator
reads. The single env is a fleet of one; the native vector env holds one row per actuator.
Both assemble their observations (:meth:`scas_env.observation.ObservationBuilder.observe`)
and infos (:func:`scas_env.info.build_info`) from these rows with one implementation, so
the two forms cannot drift apart.

Who writes a row: the env's objects own the state of one actuator (the world: crack, wear,
unit; the monitor: filters' RUL tables, detectors, flights since each filter update; the
feature memory; the episode counters) and export an explicit snapshot into a row
(``export_state(fleet, row)``); the vector env's fast flight path changes a few columns in
place for all rows at once and hands them back (``import_flight_state(fleet, row)``) before
an actuator takes a slow step (a test, a replacement, a failure, a reset).

Units: crack depth, failure depth and wear in m; features in SI (A, A/m, m, -); RUL tables
in flights; counters in slots or flights as named; money in USD.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from scas_env.fleet_kernels import true_rul

#: the two replaceable parts, in column order of every (N, 2) array
PARTS = ("spring", "seal")
#: keys of ``info["reward_terms"]`` (USD this step)
REWARD_TERMS = ("flight", "test", "no_go", "replacement", "failure")


class FleetState:
    """Arrays over ``n`` actuators (module docstring).

    Parameters: ``n`` rows; ``n_unit_features`` surrogate features (installation effects),
    ``n_particles`` per filter, ``n_features`` observed features, ``seal_critical_m`` (m),
    ``kernel_tables`` (:func:`scas_env.world.kernel_tables`); ``exact_lives``
    (``Scenario.degradation_draws = "per_part"``): the true RUL is each part's own remaining
    life (``life``: flights left, the failing one included), not the expected flights to failure;
    ``n_learning`` in-flight features the monitor learns from (their batch sums and count).

    Attributes
    ----------
    a : column name -> array with ``n`` rows (dtype and meaning in :meth:`empty`).
    terms : reward term -> (n,) USD of this step.
    wasted_now : (n, 2) true RUL thrown away by this step's preventive replacement (flights).
    table_source : per row and part, the RUL-table object last copied into the row (copying
        is skipped while it has not changed).
    """

    def __init__(
        self,
        n: int,
        *,
        n_unit_features: int,
        n_particles: int,
        n_features: int,
        seal_critical_m: float,
        kernel_tables: dict[str, tuple],
        exact_lives: bool = False,
        n_upcoming: int = 3,
        n_learning: int = 0,
    ) -> None:
        if n < 1:
            raise ValueError(f"n = {n} must be >= 1")
        i8, b = np.int64, np.bool_
        self.n = n
        #: critical seal wear (m) of the wear fraction; growth tables of the true RUL
        self.seal_critical_m = float(seal_critical_m)
        self._tables = kernel_tables
        self.exact_lives = bool(exact_lives)
        self._rul = np.empty((n, 2))
        self.a: dict[str, np.ndarray] = {
            # the actuator (world): m, m, m, -, -, standard normals of the installation effects
            "crack": np.zeros(n),
            "wear": np.zeros(n),
            "fail": np.zeros(n),
            "theta": np.ones(n),
            "wmult": np.ones(n),
            "unit_z": np.zeros((n, n_unit_features)),
            # flights each part will still fly, the failing one included ("per_part"; else inf)
            "life": np.full((n, 2), np.inf),
            # whole lives of the next parts of each kind ("per_part"; else inf)
            "upcoming": np.full((n, 2, n_upcoming), np.inf),
            # the monitor: flights since each filter's last update, detector flags, RUL tables
            "pending": np.zeros((n, 2), dtype=i8),
            "detected": np.zeros((n, 2), dtype=b),
            "rul_sorted": np.zeros((n, 2, n_particles)),
            "rul_cum_w": np.zeros((n, 2, n_particles + 1)),
            "rul_suffix_w": np.zeros((n, 2, n_particles + 1)),
            "rul_suffix_wr": np.zeros((n, 2, n_particles + 1)),
            "rul_low": np.zeros((n, 2)),
            # the feature memory: last features (SI), slots since the last test, its no-go
            "last": np.zeros((n, n_features)),
            "test_age": np.zeros(n, dtype=i8),
            # the installation's reference reading of G1, G3 (airworthiness limits; else NaN)
            "reference": np.full((n, 2), np.nan),
            "no_go": np.zeros(n, dtype=b),
            # the episode counters
            "part_age": np.zeros((n, 2), dtype=i8),
            "downtime": np.zeros(n, dtype=i8),
            "slot": np.zeros(n, dtype=i8),
            "flown": np.zeros(n, dtype=i8),
            "tests": np.zeros(n, dtype=i8),
            "no_go_count": np.zeros(n, dtype=i8),
            "cost": np.zeros(n),
            "revenue": np.zeros(n),
            "failures": np.zeros((n, 2), dtype=i8),
            "replacements": np.zeros((n, 2), dtype=i8),
            "wasted_sum": np.zeros((n, 2)),
            "wasted_count": np.zeros((n, 2), dtype=i8),
        }
        if n_learning:
            # the monitor's batch of in-flight learning features under way: sums (SI), flights
            self.a["flight_sum"] = np.zeros((n, n_learning))
            self.a["flight_count"] = np.zeros(n, dtype=i8)
        self.terms = {t: np.zeros(n) for t in REWARD_TERMS}
        self.wasted_now = np.zeros((n, len(PARTS)))
        self.table_source: list[list[Any]] = [[None, None] for _ in range(n)]

    def true_rul(self) -> np.ndarray:
        """(n, 2) flights to failure of spring and seal: the expected ones at the units' own
        rates (:func:`scas_env.fleet_kernels.true_rul`), or with ``exact_lives`` each part's
        own remaining life (the failing flight included); a scratch array, overwritten next
        call."""
        a, t = self.a, self._tables
        if self.exact_lives:
            self._rul[:] = a["life"]
            return self._rul
        true_rul(
            a["crack"], a["wear"], a["fail"], a["theta"], a["wmult"], *t["damage"],
            *t["rul_consts"], self._rul,
        )  # fmt: skip
        return self._rul

    def clear_step(self) -> None:
        """Zero this step's reward terms and wasted life (start of a step)."""
        for t in self.terms.values():
            t.fill(0.0)
        self.wasted_now.fill(0.0)


__all__ = ["PARTS", "REWARD_TERMS", "FleetState"]
