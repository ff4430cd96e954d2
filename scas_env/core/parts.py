"""The rare events of a row, in Python over the batch's arrays: a new unit, a part fitted.

A reset fits a new unit with new parts; a replacement fits one new part. Each draws from
the row's own streams (:mod:`scas_env.core.batch`): the unit from the ``parts`` stream, each
spring pair and seal set from its kind's parts stream (``spring_parts``, ``seal_parts``), so
that the k-th part of a kind fitted in an episode is the same part with the same life
whatever the policy did. A fitted part brings its own growth stream, seeded from its parts
stream; its whole life (standard flights to failure, the failing one included) is replayed
from a copy of that stream when it is fitted. A new spring pair is a new installation: its
installation effects are drawn, and the installation's reference reading of the ground
features is recorded (the mean of ``reference_tests`` tests of the healthy installation).
The monitor's filter of the part restarts from its prior.

Everything here runs a few times per episode; the flight path is
:mod:`scas_env.core.slot`.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace

import numpy as np

from prognostics.normals import Handle, fill_standard_normal, handle_of
from prognostics.resampling import systematic_resample
from scas_env.actuator.health import CRACKED_SPRING, HealthState, actuator_config
from scas_env.actuator.physics.spring import failure_depth_from_params
from scas_env.actuator.sensing import draw_window, flight_window, ground_test
from scas_env.actuator.uncertainty import (
    UnitSample,
    draw_run_conditions,
    draw_unit,
    truncated_normal,
)
from scas_env.core.filters import (
    STATUS_MESSAGES,
    age_offsets,
    learn_row,
    predict_filter,
    survive_filters,
    work_arrays,
)
from scas_env.core.flight import (
    crack_after_flights,
    crack_flights_to_failure,
    wear_after_flights,
    wear_flights_to_failure,
)
from scas_env.core.rejuvenation import record_effect, restart
from scas_env.core.setup import (
    EFFECT_FEATURES,
    FLIGHT_FEATURES,
    GROUND_FEATURES,
    MAX_LIFE_FLIGHTS,
    PARTS,
    UPCOMING_PARTS,
    lognormal_sigma,
)
from scas_env.core.state import ActuatorState, PhysicsRow

#: the streams of a row: its env's ``np_random`` hands out seeds in this order
STREAMS = ("parts", "degradation", "measure", "filter")


def seed_streams(np_random: np.random.Generator) -> dict[str, np.random.Generator]:
    """A row's streams, seeded from its env's ``np_random``: a new unit (``parts``), the
    measurement noise (``measure``), the filters (``filter``), then one parts stream per kind
    of part. (``degradation`` keeps its place in the seed sequence but is not used: each
    part grows from its own stream.)"""
    seeds = np_random.integers(0, 2**63 - 1, size=len(STREAMS))
    rngs = {name: np.random.default_rng(int(s)) for name, s in zip(STREAMS, seeds, strict=True)}
    del rngs["degradation"]
    part_seeds = np_random.integers(0, 2**63 - 1, size=len(PARTS))
    for part, s in zip(PARTS, part_seeds, strict=True):
        rngs[f"{part}_parts"] = np.random.default_rng(int(s))
    return rngs


def reset_row(batch: ActuatorState, e: int, np_random: np.random.Generator) -> None:
    """Row ``e`` starts an episode: new streams from ``np_random``, a new unit with new parts
    (or parts part-way through life, ``initial_health="random"``), the installation's
    reference, filters at their priors, counters at zero."""
    st = batch.setup
    rngs = seed_streams(np_random)
    batch.rngs[e] = rngs
    batch.set_handle(e, "measure")
    batch.set_handle(e, "filter")
    unit = draw_unit(st.world_params, rngs["parts"])
    if st.physics:
        batch.physics[e] = PhysicsRow(int(rngs["parts"].integers(0, 2**63 - 1)))
    spring = draw_unit(st.world_params, rngs["spring_parts"])
    _fit_spring(batch, e, spring, rngs["spring_parts"])
    seal = draw_unit(st.world_params, rngs["seal_parts"])
    _fit_seal(batch, e, seal)
    if st.scenario.initial_health == "random":
        _random_health(batch, e, rngs["parts"].random(2))
    if st.physics:
        fitted = _with_part(unit, "spring", spring)
        batch.physics[e].unit = _with_part(fitted, "seal", seal)
    for part in PARTS:
        _new_growth(batch, e, part, rngs[f"{part}_parts"], look_ahead=True)
    record_reference(batch, e)
    _clear_counters(batch, e)
    _reset_monitor(batch, e)
    if st.scenario.initial_health == "in_service":
        _in_service(batch, e, rngs["parts"].random(2))


def _clear_counters(batch: ActuatorState, e: int) -> None:
    a = batch.a
    for name in (
        "pending", "flight_sum", "flight_count", "batch_usage", "det_n", "detected", "broken",
        "test_age", "no_go",
        "part_age", "downtime", "slot", "flown", "tests", "no_go_count", "cost", "revenue",
        "failures", "replacements", "wasted_sum", "wasted_count", "terms", "wasted_now",
        "tally",
    ):  # fmt: skip
        a[name][e] = 0
    a["last"][e] = batch.healthy_features


def _fit_spring(batch: ActuatorState, e: int, donor: UnitSample, rng: np.random.Generator) -> None:
    """Row ``e`` takes ``donor``'s spring pair (geometry, Paris C, initial flaw) with new
    installation effects drawn from ``rng``."""
    st, a = batch.setup, batch.a
    a["crack"][e] = donor.initial_crack_m if st.scenario.crack_active else 0.0
    a["theta"][e] = donor.paris_c / st.params.spring.paris_c
    a["unit_z"][e] = st.surrogate.draw_unit_z(rng, st.unit_z_draws)
    a["fail"][e] = (
        failure_depth_from_params(
            st.params,
            wire_diameter_m=donor.wire_diameter_m[CRACKED_SPRING],
            coil_diameter_m=donor.mean_coil_diameter_m[CRACKED_SPRING],
        ).depth_m
        if st.physics
        else st.calibration.spring_failure_depth_m
    )


def _fit_seal(batch: ActuatorState, e: int, donor: UnitSample) -> None:
    """Row ``e`` takes ``donor``'s seals (its Archard coefficient), new."""
    a = batch.a
    a["wmult"][e] = donor.wear_rate_m3_n_m / batch.setup.params.seal.wear_rate_m3_n_m
    a["wear"][e] = 0.0


def _with_part(unit: UnitSample, part: str, donor: UnitSample) -> UnitSample:
    """The physics fidelity's ``unit`` with ``donor``'s ``part`` fitted (a new, checked
    :class:`UnitSample`): the spring pair (geometry, Paris C, initial flaw) or the seals."""
    if part == "spring":
        return replace(
            unit,
            wire_diameter_m=donor.wire_diameter_m,
            mean_coil_diameter_m=donor.mean_coil_diameter_m,
            paris_c=donor.paris_c,
            initial_crack_m=donor.initial_crack_m,
        )
    return replace(unit, wear_rate_m3_n_m=donor.wear_rate_m3_n_m)


def _in_service(batch: ActuatorState, e: int, used: np.ndarray) -> None:
    """Each part of row ``e`` has flown ``floor(used * life)`` standard flights (its own
    growth draws used up, its age known); its filter is the new-part prior predicted over
    them (the filter stream) and conditioned on the part having survived."""
    st, a = batch.setup, batch.a
    wm = st.world
    for p, part in enumerate(PARTS):
        life = float(a["life"][e, p])
        flights = int(used[p] * life) if math.isfinite(life) else 0
        if flights == 0:
            continue
        handle = tuple(a["h_growth"][e, p].tolist())
        if part == "spring" and st.scenario.crack_active:
            a["crack"][e] = crack_after_flights(
                float(a["crack"][e]), float(a["theta"][e]), handle, flights, *wm.damage,
                wm.cv_log_depth, wm.cv_values, wm.dormant_m,
            )  # fmt: skip
        elif part == "seal" and st.scenario.wear_active:
            rate = wm.wear_rate_m * float(a["wmult"][e])
            a["wear"][e] = wear_after_flights(
                float(a["wear"][e]), rate, wm.wear_cv, handle, flights
            )
        a["life"][e, p] -= flights
        a["part_age"][e, p] = flights
        a["pending"][e, p] = float(flights)
    predict_and_survive(batch, e)


def predict_and_survive(batch: ActuatorState, e: int) -> None:
    """Row ``e``'s filters predicted over the flights pending and conditioned on both parts
    having survived them (the filter stream; :mod:`scas_env.core.filters`)."""
    a = batch.a
    status = a["status"]
    status[e] = 0
    work = work_arrays(batch.setup.n_particles, len(batch.a["flight_sum"][e]))
    handle = tuple(a["h_filter"][e].tolist())
    filt = batch.setup.filters
    for p in range(2):
        d = float(a["pending"][e, p])
        if d > 0 and status[e] == 0:
            predict_filter(e, p, d, batch.bank, a["pending"], status, work, filt, handle)
    if status[e] == 0:
        survive_filters(e, batch.bank, status, work, filt, handle)
    a["stale"][e] = True
    raise_status(int(status[e]))


def _random_health(batch: ActuatorState, e: int, life_used: np.ndarray) -> None:
    """Parts part-way through life: each at the fraction ``life_used`` of it (in damage
    for the crack, in wear for the seals)."""
    st, a = batch.setup, batch.a
    cal, table = st.calibration, st.crack_table
    if st.scenario.crack_active and a["crack"][e] >= cal.crack_dormant_below_m:
        start = float(table.damage(np.array([a["crack"][e]]))[0])
        end = float(table.damage(np.array([a["fail"][e]]))[0])
        a["crack"][e] = float(
            table.inverse_damage(np.array([start + life_used[0] * (end - start)]))[0]
        )
    if st.scenario.wear_active:
        a["wear"][e] = life_used[1] * cal.seal_critical_wear_m


def _new_growth(
    batch: ActuatorState, e: int, part: str, rng: np.random.Generator, *, look_ahead: bool
) -> None:
    """The fitted ``part``'s own growth stream, seeded from ``rng`` (its parts stream), its
    life, and (``look_ahead``, in the observation modes that show them) the lives of the
    next parts."""
    seed = int(rng.integers(0, 2**63 - 1))
    batch.rngs[e][f"{part}_growth"] = np.random.default_rng(seed)
    batch.set_handle(e, f"{part}_growth")
    p = PARTS.index(part)
    batch.a["life"][e, p] = flights_to_failure(batch, e, part)
    if look_ahead and batch.look_ahead:
        batch.a["upcoming"][e, p] = next_lives(batch, e, part, UPCOMING_PARTS)


def flights_to_failure(batch: ActuatorState, e: int, part: str) -> float:
    """Standard flights ``part`` of row ``e`` will still fly, the failing one included, at
    its own future growth draws (a copy of its stream is replayed; inf if the fault is off
    or the crack dormant)."""
    st, a = batch.setup, batch.a
    cal, wm = st.calibration, st.world
    if part == "spring":
        if not st.scenario.crack_active or a["crack"][e] < cal.crack_dormant_below_m:
            return math.inf
    elif not st.scenario.wear_active:
        return math.inf
    with replayed(batch.rngs[e][f"{part}_growth"]) as draws:
        if part == "spring":
            return crack_flights_to_failure(
                float(a["crack"][e]), float(a["fail"][e]), float(a["theta"][e]), draws,
                *wm.damage, wm.cv_log_depth, wm.cv_values, wm.dormant_m, MAX_LIFE_FLIGHTS,
            )  # fmt: skip
        rate = wm.wear_rate_m * float(a["wmult"][e])
        return wear_flights_to_failure(
            float(a["wear"][e]), rate, wm.wear_cv, cal.seal_critical_wear_m, draws,
            MAX_LIFE_FLIGHTS,
        )  # fmt: skip


@contextmanager
def replayed(rng: np.random.Generator) -> Iterator[Handle]:
    """Draw ahead from ``rng`` (its kernel handle), then put it back where it was: what drawing
    from a ``copy.deepcopy`` of it gives, ~15x faster (the bit generator's state saved and
    restored; tested equal)."""
    bit_generator = rng.bit_generator
    saved = bit_generator.state
    try:
        with bit_generator.lock:
            yield handle_of(rng)
    finally:
        bit_generator.state = saved


def next_lives(batch: ActuatorState, e: int, part: str, count: int) -> list[float]:
    """The whole lives (standard flights) of the next ``count`` parts of this kind that row
    ``e``'s parts stream will supply (a copy of it: nothing of the row moves): what a
    clairvoyant oracle knows."""
    if isinstance(count, bool) or not isinstance(count, int) or count < 0:
        raise ValueError(f"count = {count!r} must be an integer >= 0")
    scratch = batch.scratch_row(e)
    rng = batch.rngs[e][f"{part}_parts"]
    saved = rng.bit_generator.state
    lives = []
    try:
        for _ in range(count):
            _fit_part(scratch, 0, part, rng, look_ahead=False)
            lives.append(float(scratch.a["life"][0, PARTS.index(part)]))
    finally:
        rng.bit_generator.state = saved
    return lives


def _fit_part(
    batch: ActuatorState, e: int, part: str, rng: np.random.Generator, *, look_ahead: bool
) -> None:
    """Row ``e`` gets a new ``part`` drawn from ``rng`` (its kind's parts stream), with its
    growth stream and life."""
    st = batch.setup
    donor = draw_unit(st.world_params, rng)
    if part == "spring":
        _fit_spring(batch, e, donor, rng)
    else:
        _fit_seal(batch, e, donor)
    if st.physics:
        batch.physics[e].unit = _with_part(batch.physics[e].unit, part, donor)
    _new_growth(batch, e, part, rng, look_ahead=look_ahead)


def replace_part(batch: ActuatorState, e: int, part: str, *, failed: bool) -> None:
    """Row ``e`` fits a new ``part``: a preventive replacement (its cost, and the true life
    thrown away, counted) or the replacement of a failed part (costed with the failure)."""
    st, a = batch.setup, batch.a
    p = PARTS.index(part)
    if not failed:
        cost = (
            st.costs.spring_replacement_usd if part == "spring" else st.costs.seal_replacement_usd
        )
        a["terms"][e, 3] -= cost
        wasted = min(float(a["life"][e, p]), st.scenario.rul_cap_flights)
        a["wasted_sum"][e, p] += wasted
        a["wasted_count"][e, p] += 1
        a["wasted_now"][e, p] = wasted
    a["replacements"][e, p] += 1
    _fit_part(batch, e, part, batch.rngs[e][f"{part}_parts"], look_ahead=True)
    if part == "spring":
        record_reference(batch, e)
    reset_filter(batch, e, part)
    a["no_go"][e] = False
    a["part_age"][e, p] = 0


def record_reference(batch: ActuatorState, e: int) -> None:
    """The installation's reference reading of G1 and G3, recorded at fitting: the mean of
    ``reference_tests`` tests of the installation with healthy parts (the measure stream), as
    the world measures them (``Setup.world_features``)."""
    st = batch.setup
    rng = batch.rngs[e]["measure"]
    n = int(st.scenario.reference_tests)
    if st.physics:
        tests = [physics_test(batch, e, rng, healthy=True) for _ in range(n)]
    else:
        idx = st.world.ground_idx.tolist()
        unit_z = batch.a["unit_z"][e]
        tests = [st.world_features.sample_list(0.0, 0.0, unit_z, rng, idx) for _ in range(n)]
    batch.a["reference"][e] = [math.fsum(t[k] for t in tests) / n for k in range(2)]


def _reset_monitor(batch: ActuatorState, e: int) -> None:
    """Both filters at their priors: the spring's, then the seals' (which keep the
    installation's effects, here the priors), then, for parts of unknown age, spread over
    their lives."""
    a = batch.a
    n = batch.setup.n_particles
    a["w"][e] = 1.0 / n
    a["log_w"][e] = -math.log(n)
    a["aux"][e, :, 0::2] = 0.0
    a["aux"][e, :, 1::2] = 1.0
    reset_filter(batch, e, "spring")
    reset_filter(batch, e, "seal")
    if batch.setup.scenario.initial_health == "random":
        _spread_over_life(batch, e)


def reset_filter(batch: ActuatorState, e: int, part: str) -> None:
    """A new ``part`` is fitted to row ``e``: the batch of in-flight features flown with the
    old one is learnt from first, then its filter restarts from the prior (a new spring pair
    is a new installation: every installation effect back to N(0, 1), and the spring
    filter's history for resample-move emptied; new seals keep the installation's,
    collapsed to one Gaussian), its detector is cleared. With the seal filter's
    resample-move (``Scenario.rejuvenation = "resample_move_both"``) a new seal's history
    starts with those beliefs, and a new spring pair writes N(0, 1) beliefs into the
    seal's history (:func:`scas_env.core.rejuvenation.record_effect`). The seal particles'
    offsets of the spring estimate (``Scenario.seal_cross_persistence``) are drawn anew
    with a new spring pair and carried over to new seals (:func:`_spring_errors_kept`)."""
    st, a = batch.setup, batch.a
    learn_now(batch, e)
    rng = batch.rngs[e]["filter"]
    n = st.n_particles
    p = PARTS.index(part)
    if part == "spring":
        a0, s0 = st.params.spring.initial_crack_m, st.params.uncertainty.initial_crack_sigma_m
        x0 = truncated_normal(rng, a0, s0, lower=0.0, upper=st.calibration.spring_failure_depth_m,
                              size=n)  # fmt: skip
        if not st.scenario.crack_active:  # no crack grows: the world's spring stays at 0
            x0 = np.zeros(n)
        _reset_cloud(batch, e, p, x0, _lognormal(rng, lognormal_sigma(st.params, part), n))
        a["aux"][e, :, 0::2] = 0.0
        a["aux"][e, :, 1::2] = 1.0
        restart(e, batch.bank)
        if st.filters.move.seal:  # the seal's installation effects, from here on
            _record_seal_effects(batch, e)
        _new_spring_errors(batch, e, rng)
    else:
        w = a["w"][e, 1]
        kept = [
            _mixture_moments(w, a["aux"][e, 1, k], a["aux"][e, 1, k + 1])
            for k in range(0, 2 * len(EFFECT_FEATURES[1]), 2)
        ]
        errors = _spring_errors_kept(batch, e, rng)
        _reset_cloud(batch, e, p, 0.0, _lognormal(rng, lognormal_sigma(st.params, part), n))
        for j, (mean, var) in enumerate(kept):
            a["aux"][e, 1, 2 * j] = mean
            a["aux"][e, 1, 2 * j + 1] = var
        if st.filters.move.seal:
            restart(e, batch.bank, 1)
            _record_seal_effects(batch, e)
        if errors is not None:
            a["aux"][e, 1, st.filters.persistence[1]] = errors
    a["det_n"][e, p] = 0
    a["detected"][e, p] = False
    a["pending"][e, p] = 0.0
    a["stale"][e] = True


def _new_spring_errors(batch: ActuatorState, e: int, rng: np.random.Generator) -> None:
    """With ``Scenario.seal_cross_persistence``: each seal particle's offset of the spring
    estimate drawn anew, N(0, 1): a new spring pair's estimate has an error of its own."""
    row = batch.setup.filters.persistence[1]
    if row >= 0:
        with rng.bit_generator.lock:
            fill_standard_normal(handle_of(rng), batch.a["aux"][e, 1, row])


def _spring_errors_kept(
    batch: ActuatorState, e: int, rng: np.random.Generator
) -> np.ndarray | None:
    """With ``Scenario.seal_cross_persistence``, before a new seal set: the offsets of the
    spring estimate resampled by the old seal filter's weights (systematic), then taken
    through the AR(1) over the flights the seal filter had pending (the new cloud drops
    them); None (the offsets stay as they are) without the option or while the spring pair
    has not flown since its fitting (its offsets are the prior draws of that fitting, which
    the old seals' weights say nothing about: a fitting of both, an episode's start). The
    spring and its estimate stay, so what the old seals' data said about the estimate's
    error carries over; the new seals' states are independent of it (their prior)."""
    a = batch.a
    rho, row = batch.setup.filters.persistence
    if row < 0 or a["part_age"][e, 0] == 0:
        return None
    kept = a["aux"][e, 1, row][systematic_resample(a["w"][e, 1], rng)]
    d = float(a["pending"][e, 1])
    if d > 0.0:
        with rng.bit_generator.lock:
            age_offsets(kept, rho, d, handle_of(rng))
    return kept


def _record_seal_effects(batch: ActuatorState, e: int) -> None:
    """Row ``e``'s seal filter's installation-effect beliefs (one Gaussian per feature, the
    same for every particle) appended to its history as belief rows."""
    n_slots = len(EFFECT_FEATURES[1])
    batch.ensure_history(np.array([e], dtype=np.int64), n_slots)
    a = batch.a
    for j in range(n_slots):
        mean, var = float(a["aux"][e, 1, 2 * j, 0]), float(a["aux"][e, 1, 2 * j + 1, 0])
        record_effect(e, 1, 2 * j, mean, var, batch.bank)


def _reset_cloud(batch: ActuatorState, e: int, p: int, x0, theta0: np.ndarray) -> None:
    """Filter p of row e: particles at ``x0``, growth multipliers ``theta0`` (> 0), uniform
    weights (:meth:`prognostics.particle_filter.ParticleFilter.reset`)."""
    a = batch.a
    n = batch.setup.n_particles
    x = a["x"][e, p]
    x[...] = x0
    if not (np.isfinite(x).all() and np.isfinite(theta0).all()):
        raise ValueError("a filter prior gave a non-finite particle")
    if not (theta0 > 0.0).all():
        raise ValueError("theta0 must be > 0 for every particle")
    a["log_theta"][e, p] = np.log(theta0)
    a["w"][e, p] = 1.0 / n
    a["log_w"][e, p] = -math.log(n)


def _lognormal(rng: np.random.Generator, sigma: float, n: int) -> np.ndarray:
    """exp(sigma z), z drawn as numba kernels draw normals from ``rng`` (the same values)."""
    z = np.empty(n)
    with rng.bit_generator.lock:
        fill_standard_normal(handle_of(rng), z)
    return np.exp(sigma * z)


def _mixture_moments(w: np.ndarray, mean: np.ndarray, var: np.ndarray) -> tuple[float, float]:
    """Mean and variance of the weighted mixture of Gaussians N(mean_i, var_i)."""
    mu = float(w @ mean)
    return mu, float(w @ var + w @ (mean - mu) ** 2)


def _spread_over_life(batch: ActuatorState, e: int) -> None:
    """Priors of parts part-way through life: each particle at a uniform fraction of its own
    life (in damage for the crack, in wear for the seals)."""
    st, a = batch.setup, batch.a
    rng = batch.rngs[e]["filter"]
    model, n = st.spring_process, st.n_particles
    x, theta = np.array(a["x"][e, 0]), np.exp(a["log_theta"][e, 0])
    start = model.damage(np.maximum(x, model.grid[0]))
    end = model.damage(np.array([st.calibration.spring_failure_depth_m]))[0]
    used = rng.random(n) * np.maximum(end - start, 0.0)
    if st.scenario.crack_active:  # a fault switched off keeps its part new (as the world)
        _reset_cloud(batch, e, 0, model.inverse_damage(start + used), theta)
    wear = rng.random(n) * st.calibration.seal_critical_wear_m
    if st.scenario.wear_active:
        _reset_cloud(batch, e, 1, wear, np.exp(a["log_theta"][e, 1]))
    a["stale"][e] = True


def learn_now(batch: ActuatorState, e: int) -> None:
    """Row ``e``'s filters learn from the batch of in-flight features under way (before a
    new part is fitted: those flights were flown with the old one)."""
    a = batch.a
    if a["flight_count"][e] == 0:
        return
    status = a["status"]
    status[e] = 0
    work = work_arrays(batch.setup.n_particles, len(batch.a["flight_sum"][e]))
    handle = tuple(a["h_filter"][e].tolist())
    learn_row(e, batch.bank, a["pending"], a["flight_sum"], a["flight_count"], a["batch_usage"],
              status, work, batch.setup.filters, handle)  # fmt: skip
    a["stale"][e] = True
    raise_status(int(status[e]))


def raise_status(code: int) -> None:
    """Raise what a filter kernel's non-zero row status means; nothing for 0."""
    if code:
        error, message = STATUS_MESSAGES[code]
        raise error(f"a particle-filter update failed: {message}; call reset()")


def _physics_config(batch: ActuatorState, e: int, rng: np.random.Generator, healthy: bool):
    st, a = batch.setup, batch.a
    health = HealthState(
        crack_depth_m=0.0 if healthy else float(a["crack"][e]),
        seal_wear_m=0.0 if healthy else float(a["wear"][e]),
    )
    conditions = draw_run_conditions(st.params, rng)
    return actuator_config(st.params, unit=batch.physics[e].unit, conditions=conditions,
                           health=health)  # fmt: skip


def physics_test(
    batch: ActuatorState, e: int, rng: np.random.Generator, *, healthy: bool = False
) -> list[float]:
    """A simulated pre-flight test of row ``e`` (its parts healthy if ``healthy``): G1, G3."""
    config = _physics_config(batch, e, rng, healthy)
    feats = ground_test(batch.setup.params, config, rng).features
    return [feats[f] for f in GROUND_FEATURES]


def _library_window(batch: ActuatorState, e: int, rng: np.random.Generator):
    """This flight's window from row ``e``'s library (None: draw a new one from ``rng``)."""
    st = batch.setup
    size = int(st.scenario.window_library)
    if size == 0:
        return None
    row = batch.physics[e]
    k = int(rng.integers(size))
    if k not in row.windows:
        seeded = np.random.default_rng((row.library_seed, k))
        row.windows[k] = draw_window(st.params, seeded, st.params.mission.flight_window_s)
    return row.windows[k]


def physics_flight(batch: ActuatorState, e: int, rng: np.random.Generator) -> np.ndarray:
    """A simulated flight window of row ``e`` at its parts' state: the in-flight features."""
    st = batch.setup
    config = _physics_config(batch, e, rng, healthy=False)
    window = flight_window(
        st.params, config, rng, st.params.mission.flight_window_s,
        window=_library_window(batch, e, rng),
    )  # fmt: skip
    return np.array([window.features[f] for f in FLIGHT_FEATURES])


__all__ = [
    "STREAMS",
    "flights_to_failure",
    "learn_now",
    "next_lives",
    "physics_flight",
    "physics_test",
    "raise_status",
    "record_reference",
    "replace_part",
    "reset_filter",
    "reset_row",
    "seed_streams",
]
