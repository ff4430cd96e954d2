"""The numba kernel of one slot over the rows of a batch: test, fly, learn, book.

A slot is one flight opportunity of the single env, or one day of a fleet. :func:`slot_rows`
runs, for each listed row and its action (:data:`FLY`, :data:`TEST_AND_FLY`, a replacement,
:data:`STAND_BY`), what a slot does on the common path, in phases over all rows:

1. on the ground (downtime left) or standing by: nothing; a replacement asked for: left to
   Python (``event``); a pre-flight test (asked for, or before every flight): the ground
   features drawn, the filters and detectors updated, the go/no-go against the
   installation's reference;
2. the rows of one aircraft (``group``) fly together: only when every row of the group may
   go (no failed test, no hold); then ``flights[e]`` flights, flight by flight: features
   drawn at the parts' state, the parts grown by their own draws for the row's mission type
   (``mtype``), the learning batch filled and learnt from when full. A part that reaches its
   critical value fails the flight: the flight earns nothing for any row of the group, and
   the group flies no further that slot. With a test before every flight, the rows of a
   group still flying test again (as in phase 1) before each flight after the first; a
   no-go holds the group for the rest of the slot (the flights before it stay flown);
3. the slot's bookkeeping (:func:`close_row`).

Python takes the rows left with an event (a replacement; a failure, ``event = FAILURE``, the
failed parts in ``failed``) or a filter error (``status``), handles them with the row's part
streams (:mod:`scas_env.core.parts`) and then closes their slot. The physics fidelity
measures in Python and calls :func:`test_measured` and :func:`fly_measured`, the same
updates with given features.

Arrays (one row per actuator; :class:`scas_env.core.state.ActuatorState` names them):
``world = (crack, wear, fail, theta, wmult, unit_z, life, reference)``,
``monitor = (bank, pending, flight_sum, flight_count, stale, det_buf, det_n, detected,
batch_usage)``, ``memory = (last, test_age, no_go)``, ``books = (part_age, downtime, slot,
flown, tests, no_go_count, cost, revenue)``, ``handles = (measure, filter, growth)``, ``out
= (terms, reward, flew, failed, event, status)``; ``plan = (actions, flights, group, mtype,
flight_value)`` per row; ``prices = (test, no-go inspection, failure)`` in USD.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from prognostics.normals import standard_normal
from scas_env.core.filters import learn_row, test_row, work_arrays
from scas_env.core.flight import crack_after_flight, features_at, interp_scalar, wear_after_flight

#: actions of a row in a slot
FLY, TEST_AND_FLY, REPLACE_SPRING, REPLACE_SEAL, STAND_BY, REPLACE_BOTH = range(6)
#: ``event`` of a row whose flight ended in a failure (2, 3, 5: the replacement asked for)
FAILURE = 4
#: reward-term columns
T_FLIGHT, T_TEST, T_NO_GO, T_REPLACEMENT, T_FAILURE = range(5)


@njit(cache=True, inline="always")
def _handle(h: np.ndarray, e: int) -> tuple:
    return (h[e, 0], h[e, 1], h[e, 2])


@njit(cache=True, error_model="numpy")
def _quantile(ordered: np.ndarray, q: float) -> float:
    """``np.quantile(values, q, method="linear")`` of sorted values, numpy's arithmetic
    (:func:`prognostics.detection._linear_quantile`)."""
    n = ordered.size
    virtual = (n - 1) * q
    lo = min(max(math.floor(virtual), 0), n - 1)
    hi = min(lo + 1, n - 1)
    gamma = virtual - lo
    a, b = ordered[lo], ordered[hi]
    diff = b - a
    if gamma >= 0.5:
        return b - diff * (1 - gamma)
    return a + diff * gamma


@njit(cache=True, inline="always")
def detect(e: int, p: int, value: float, det_buf: np.ndarray, det_n: np.ndarray,
           detected: np.ndarray, det: tuple) -> None:  # fmt: skip
    """Part p's section-5.1 detector of row e reads ``value``: the window of its last
    ``W`` values against the healthy baseline's percentiles
    (:class:`prognostics.detection.PercentileDetector`); the flag, once raised, stays."""
    thresholds, rising, falling, window, fraction = det
    det_buf[e, p, det_n[e, p] % window] = value
    det_n[e, p] += 1
    if det_n[e, p] < window:
        return
    ordered = np.sort(det_buf[e, p, :window])
    low_q, high_q = _quantile(ordered, 1.0 - fraction), _quantile(ordered, fraction)
    alarm = (rising[p] and low_q > thresholds[p, 1]) or (falling[p] and high_q < thresholds[p, 0])
    detected[e, p] = alarm or detected[e, p]


@njit(cache=True, inline="always")
def close_row(e: int, books: tuple, memory: tuple, out: tuple) -> None:
    """The end of row e's slot: downtime, slot and ages advance (the ages by the flights
    flown); the reward and the running cost and revenue take the slot's terms, summed in
    :data:`REWARD_TERMS` order."""
    part_age, downtime, slot, flown, _, _, cost, revenue = books
    terms, reward, flew = out[0], out[1], out[2]
    downtime[e] = max(downtime[e] - 1, 0)
    slot[e] += 1
    memory[1][e] += 1
    if flew[e] > 0:
        flown[e] += flew[e]
        part_age[e, 0] += flew[e]
        part_age[e, 1] += flew[e]
    t = terms[e]
    reward[e] = ((((0.0 + t[0]) + t[1]) + t[2]) + t[3]) + t[4]
    cost[e] -= (((0.0 + t[1]) + t[2]) + t[3]) + t[4]
    revenue[e] += t[0]


@njit(cache=True, error_model="numpy")
def close_rows(rows: np.ndarray, books: tuple, memory: tuple, out: tuple) -> None:
    """:func:`close_row` for each row of ``rows``."""
    for e in rows:
        close_row(e, books, memory, out)


@njit(cache=True, inline="always")
def _tested(e: int, g1: float, g3: float, every_flight: bool, world: tuple, monitor: tuple,
            memory: tuple, books: tuple, handles: tuple, out: tuple, go_limits: np.ndarray,
            prices: tuple, filt: tuple, det: tuple, n_flight: int,
            work: tuple) -> bool:  # fmt: skip
    """A pre-flight test of row e read G1 = ``g1``, G3 = ``g3``: filters, detectors,
    go/no-go, feature memory, counters and terms. Returns go (False also on a filter error,
    whose status Python raises)."""
    reference = world[7]
    bank, pending, flight_sum, flight_count, stale, det_buf, det_n, detected, usage = monitor
    last, test_age, no_go = memory
    terms, status = out[0], out[5]
    c1, c3 = test_row(
        e, g1, g3, bank, pending, flight_sum, flight_count, usage, status, work, filt,
        _handle(handles[1], e),
    )  # fmt: skip
    stale[e] = True
    if status[e] != 0:
        return False
    detect(e, 0, c1, det_buf, det_n, detected, det)
    detect(e, 1, c3, det_buf, det_n, detected, det)
    passed = abs(g1 - reference[e, 0]) <= go_limits[0] and abs(g3 - reference[e, 1]) <= go_limits[1]
    last[e, n_flight] = g1
    last[e, n_flight + 1] = g3
    test_age[e] = 0
    no_go[e] = not passed
    books[4][e] += 1
    terms[e, T_TEST] = 0.0 if every_flight else -prices[0]
    if not passed:
        books[5][e] += 1
        terms[e, T_NO_GO] = -prices[1]
    return passed


@njit(cache=True, inline="always")
def _ground_test(e: int, every_flight: bool, world: tuple, monitor: tuple, memory: tuple,
                 books: tuple, handles: tuple, out: tuple, go_limits: np.ndarray,
                 prices: tuple, wm: tuple, filt: tuple, det: tuple, ground_z: np.ndarray,
                 ground: np.ndarray, work: tuple) -> bool:  # fmt: skip
    """Row e's pre-flight test at its parts' state now: two normals of its measure stream,
    the ground features (G1, G3), then :func:`_tested`. Returns go."""
    crack, wear, fail, unit_z = world[0], world[1], world[2], world[5]
    c = min(crack[e] / fail[e], 1.0)
    w = min(wear[e] / wm.seal_critical_m, 1.0)
    measure = _handle(handles[0], e)
    ground_z[0] = standard_normal(measure)
    ground_z[1] = standard_normal(measure)
    features_at(c, w, unit_z[e], ground_z, wm.crack_grid, wm.wear_grid, wm.stack,
                wm.ground_idx, ground)  # fmt: skip
    return _tested(
        e, ground[0], ground[1], every_flight, world, monitor, memory, books, handles, out,
        go_limits, prices, filt, det, wm.flight_idx.size, work,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _grow(e: int, k: int, world: tuple, handles: tuple, wm: tuple, out: tuple) -> bool:
    """Row e's parts grow by one flight of mission type ``k`` (each by the next draw of its
    own stream); its standard-flight equivalent off each part's life (exact for the standard
    mission, 1; a damaging type's multiplier at the crack's depth, first order). Returns
    whether a part reached its critical value (``failed`` says which)."""
    crack, wear, fail, theta, wmult = world[0], world[1], world[2], world[3], world[4]
    life = world[6]
    failed = out[3]
    hg = handles[2]
    z_spring = standard_normal((hg[e, 0, 0], hg[e, 0, 1], hg[e, 0, 2]))
    z_seal = standard_normal((hg[e, 1, 0], hg[e, 1, 1], hg[e, 1, 2]))
    if k == 0:
        life[e, 0] -= 1.0
        life[e, 1] -= 1.0
    else:
        life[e, 0] -= interp_scalar(crack[e], wm.damage[0], wm.type_crack_mult[k])
        life[e, 1] -= wm.type_wear_mult[k]
    c = crack[e]
    if wm.crack_active:
        d = wm.damage
        c = crack_after_flight(
            c, theta[e], z_spring, 1.0, d[0], wm.type_rate[k], wm.type_cum[k], d[3], d[4],
            wm.type_cv_log_depth[k], wm.type_cv[k], wm.dormant_m,
        )  # fmt: skip
    w = wear[e]
    if wm.wear_active:
        w = wear_after_flight(
            w, wm.wear_rate_m * wmult[e], wm.type_wear_cv[k], z_seal, wm.type_wear_mult[k]
        )
    crack[e], wear[e] = c, w
    failed[e, 0] = c >= fail[e]
    failed[e, 1] = w >= wm.seal_critical_m
    return failed[e, 0] or failed[e, 1]


@njit(cache=True, inline="always")
def _usage(e: int, k: int, bank: tuple, wm: tuple) -> tuple:
    """The standard flights one flight of mission type ``k`` counts as in row e's filters:
    the type's crack multiplier at the spring filter's mean depth, its wear multiplier."""
    if k == 0:
        return 1.0, 1.0
    bx, bw = bank[0], bank[2]
    depth = np.dot(bw[e, 0], bx[e, 0])
    return interp_scalar(depth, wm.damage[0], wm.type_crack_mult[k]), wm.type_wear_mult[k]


@njit(cache=True, inline="always")
def _flown(e: int, feats: np.ndarray, broke: bool, k: int, interval: int, monitor: tuple,
           memory: tuple, out: tuple, prices: tuple, filt: tuple, learn_cols: np.ndarray,
           handles: tuple, work: tuple, wm: tuple) -> None:  # fmt: skip
    """After row e's flight: its usage pending in both filters; a failure's terms and event,
    or the features into the memory and the learning batch (learnt from when full)."""
    bank, pending, flight_sum, flight_count, stale = monitor[:5]
    usage = monitor[8]
    last = memory[0]
    terms, event, status = out[0], out[4], out[5]
    u_spring, u_seal = _usage(e, k, bank, wm)
    pending[e, 0] += u_spring
    pending[e, 1] += u_seal
    if broke:
        terms[e, T_FAILURE] = -prices[2]
        event[e] = FAILURE
        return
    for m in range(feats.size):
        last[e, m] = feats[m]
    usable = True
    for j in range(learn_cols.size):
        if not math.isfinite(feats[learn_cols[j]]):
            usable = False
    if usable and learn_cols.size:
        for j in range(learn_cols.size):
            flight_sum[e, j] += feats[learn_cols[j]]
        flight_count[e] += 1
        usage[e, 0] += u_spring
        usage[e, 1] += u_seal
        if flight_count[e] >= interval:
            learn_row(
                e, bank, pending, flight_sum, flight_count, usage, status, work, filt,
                _handle(handles[1], e),
            )  # fmt: skip
            stale[e] = True


@njit(cache=True, error_model="numpy")
def slot_rows(
    rows: np.ndarray,
    plan: tuple,
    every_flight: bool,
    interval: int,
    world: tuple,
    monitor: tuple,
    memory: tuple,
    books: tuple,
    handles: tuple,
    out: tuple,
    go_limits: np.ndarray,
    prices: tuple,
    wm: tuple,
    filt: tuple,
    det: tuple,
    learn_cols: np.ndarray,
) -> None:
    """One slot of each row ``e`` of ``rows`` under its ``plan`` (module docstring). Rows
    left with ``event[e] != 0`` (a replacement or a failure) or ``status[e] != 0`` (a filter
    error) are not closed: Python takes them on."""
    actions, flights, group, mtype, flight_value = plan
    crack, wear, fail, unit_z = world[0], world[1], world[2], world[5]
    downtime, no_go = books[1], memory[2]
    terms, flew, failed, event, status = out[0], out[2], out[3], out[4], out[5]
    n_flight = wm.flight_idx.size
    work = work_arrays(monitor[0][0].shape[2], learn_cols.size)
    ground_z = np.empty(2)
    ground = np.empty(2)
    flight_z = np.empty(n_flight)
    feats = np.empty(n_flight)
    n = actions.size
    wants = np.zeros(n, dtype=np.bool_)
    go = np.ones(n, dtype=np.bool_)  # per group
    broken_at = np.full(n, -1, dtype=np.int64)  # per group: the flight a part failed on
    most = 0
    # 1. the ground: replacements, tests, who may fly
    for e in rows:
        terms[e, :] = 0.0
        flew[e] = 0
        failed[e, 0] = False
        failed[e, 1] = False
        event[e] = 0
        status[e] = 0
        a = actions[e]
        if a in (REPLACE_SPRING, REPLACE_SEAL, REPLACE_BOTH):
            event[e] = a
            continue
        if a == STAND_BY or downtime[e] > 0:
            continue
        ok = not no_go[e]
        if every_flight or a == TEST_AND_FLY:
            ok = _ground_test(
                e, every_flight, world, monitor, memory, books, handles, out, go_limits,
                prices, wm, filt, det, ground_z, ground, work,
            )  # fmt: skip
            if status[e] != 0:
                continue
        wants[e] = True
        if not ok:
            go[group[e]] = False
        most = max(most, flights[e])
    # 2. the flights, flight by flight; a failure ends its group's flying after that flight
    # (every row of the group flies the failing flight, whatever its index); with a test
    # before every flight, every row still flying tests again before each later flight, and
    # a no-go holds its group for the rest of the slot
    for f in range(most):
        if every_flight and f > 0:
            held = np.zeros(n, dtype=np.bool_)  # per group
            for e in rows:
                g = group[e]
                if not (wants[e] and go[g] and broken_at[g] < 0 and f < flights[e]):
                    continue
                ok = _ground_test(
                    e, every_flight, world, monitor, memory, books, handles, out, go_limits,
                    prices, wm, filt, det, ground_z, ground, work,
                )  # fmt: skip
                if status[e] != 0:
                    wants[e] = False
                elif not ok:
                    held[g] = True
            for e in rows:
                if held[group[e]]:
                    go[group[e]] = False
        for e in rows:
            g = group[e]
            if not (wants[e] and go[g] and broken_at[g] in (-1, f) and f < flights[e]):
                continue
            c = min(crack[e] / fail[e], 1.0)
            w = min(wear[e] / wm.seal_critical_m, 1.0)
            measure = _handle(handles[0], e)
            for m in range(n_flight):
                flight_z[m] = standard_normal(measure)
            features_at(c, w, unit_z[e], flight_z, wm.crack_grid, wm.wear_grid, wm.stack,
                        wm.flight_idx, feats)  # fmt: skip
            k = mtype[e]
            broke = _grow(e, k, world, handles, wm, out)
            _flown(e, feats, broke, k, interval, monitor, memory, out, prices, filt,
                   learn_cols, handles, work, wm)  # fmt: skip
            if broke:
                broken_at[g] = f
        for e in rows:  # the flight's value, unless its aircraft lost it to a failure
            g = group[e]
            if wants[e] and go[g] and f < flights[e] and (broken_at[g] < 0 or broken_at[g] > f):
                flew[e] += 1
                terms[e, T_FLIGHT] += flight_value[e]
    # 3. the books
    for e in rows:
        if event[e] == 0 and status[e] == 0:
            close_row(e, books, memory, out)


@njit(cache=True, error_model="numpy")
def test_measured(
    e: int, g1: float, g3: float, every_flight: bool, world: tuple, monitor: tuple,
    memory: tuple, books: tuple, handles: tuple, out: tuple, go_limits: np.ndarray,
    prices: tuple, filt: tuple, det: tuple, n_flight: int,
) -> bool:  # fmt: skip
    """A pre-flight test of row e whose features were measured outside (the physics
    fidelity): the updates of :func:`slot_rows`. Returns go."""
    work = work_arrays(monitor[0][0].shape[2], filt.learn_part.size)
    return _tested(e, g1, g3, every_flight, world, monitor, memory, books, handles, out,
                   go_limits, prices, filt, det, n_flight, work)  # fmt: skip


@njit(cache=True, error_model="numpy")
def fly_measured(
    e: int, feats: np.ndarray, k: int, interval: int, world: tuple, monitor: tuple,
    memory: tuple, handles: tuple, out: tuple, prices: tuple, wm: tuple, filt: tuple,
    learn_cols: np.ndarray,
) -> bool:  # fmt: skip
    """A flight of mission type ``k`` of row e whose features were measured outside at the
    parts' state before it (the physics fidelity): growth and updates of :func:`slot_rows`
    (NaN features if it failed). Returns whether a part failed."""
    work = work_arrays(monitor[0][0].shape[2], learn_cols.size)
    broke = _grow(e, k, world, handles, wm, out)
    if broke:
        feats[:] = np.nan
    _flown(e, feats, broke, k, interval, monitor, memory, out, prices, filt, learn_cols,
           handles, work, wm)  # fmt: skip
    return broke


__all__ = [
    "FAILURE",
    "FLY",
    "REPLACE_BOTH",
    "REPLACE_SEAL",
    "REPLACE_SPRING",
    "STAND_BY",
    "TEST_AND_FLY",
    "close_row",
    "close_rows",
    "detect",
    "fly_measured",
    "slot_rows",
    "test_measured",
]
