"""Data behind the paper's physics figures ([DJS20] Figs. 3, 4, 5, 7a, 7b); no plotting here.

Each ``fig*`` function runs the library's physics for the nominal unit at nominal operating
conditions and returns a frozen dataclass of float64 arrays (read-only) with a ``to_dict()``
that gives JSON-serialisable lists. :mod:`experiments.paper.figures` draws them.

* Fig. 3 (:func:`fig3_spring_rate`): spring rate (eq. 1) and cracked-coil rate (eq. 5) against
  crack depth, with the exact polar moment and the printed eq. 6 (ref §0.11).
* Fig. 4 (:func:`fig4_crack_growth`): crack depth against flights for a few Paris-C
  multipliers theta, from the per-flight growth-rate table integrated exactly:
  a(n) = I^-1(I(a0) + n theta), I(a) = int da / g(a) (``prognostics.degradation_models``).
* Fig. 5 (:func:`fig5_frequency_response`): closed-loop response X/X_cmd at several seal-wear
  levels, and the -3 dB cut-off against the leakage coefficient K_i1 and the wear, with the
  10% drop that defines the critical wear ([DJS20] §2.2.2).
* Fig. 7a (:func:`fig7a_null_bias`): servovalve current in the pre-flight test (noise off) for
  several crack depths, and the null-bias current against depth.
* Fig. 7b (:func:`fig7b_seal_gain`): current and position in the pre-flight test for several
  wear levels, and the servo gain |X/X_cmd| at 1 Hz against wear.

>>> d = fig3_spring_rate(ScasParams(), n_points=5)
>>> round(d.healthy_rate_n_m), bool(d.spring_rate_exact_n_m[-1] < d.healthy_rate_n_m)
(16940, True)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
import numpy.typing as npt

from prognostics.degradation_models import paris_crack_model
from scas_env.actuator.bandwidth import (
    SealCriterion,
    closed_loop_gain,
    cutoff_frequency_hz,
    seal_criterion,
)
from scas_env.actuator.flight_damage import (
    CrackRateTable,
    crack_rate_table,
    load_spectrum_from_physics,
)
from scas_env.actuator.health import HealthState, actuator_config, leakage_at
from scas_env.actuator.missions import MissionProfile, preflight_test_command
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.actuator import ActuatorRun, simulate
from scas_env.actuator.physics.spring import (
    coil_stiffness_n_per_m,
    failure_depth_from_params,
    spring_rate_from_params,
)

FloatArray = npt.NDArray[np.float64]

#: Paris-C multipliers theta of the Fig. 4 curves (a slow, the nominal and a fast unit).
DEFAULT_GROWTH_MULTIPLIERS = (0.7, 1.0, 1.4)
#: Seal wear of the Fig. 5 responses, as fractions of the critical wear.
DEFAULT_RESPONSE_WEAR_FRACTIONS = (0.0, 0.5, 0.8, 1.0, 1.2)
#: Seal wear of the Fig. 7b traces, as fractions of the critical wear.
DEFAULT_TRACE_WEAR_FRACTIONS = (0.0, 0.5, 1.0, 1.5, 2.0)
#: Crack depth of the Fig. 7a traces, as fractions of the failure depth.
DEFAULT_TRACE_DEPTH_FRACTIONS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: Frequency of the Fig. 7b servo gain (Hz), inside the SCAS band (Table 1: 0.8-2 Hz).
GAIN_FREQUENCY_HZ = 1.0


def _jsonable(value: Any) -> Any:
    """Arrays to nested lists, numpy scalars to Python, non-finite floats to None."""
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()] if value.ndim else _jsonable(value.item())
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


class _Curves:
    """Mixin: read-only float64 copies of array fields and a JSON-ready ``to_dict``."""

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, (np.ndarray, list, tuple)):
                arr = np.array(value, dtype=np.float64)
                arr.setflags(write=False)
                object.__setattr__(self, f.name, arr)

    def to_dict(self) -> dict[str, Any]:
        """Field name -> value, arrays as (nested) lists; non-finite floats become None."""
        return {f.name: _jsonable(getattr(self, f.name)) for f in fields(self)}


# ------------------------------------------------------------------------ input checks
def _fractions(name: str, values: Sequence[float]) -> FloatArray:
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim != 1 or arr.size < 1 or not np.all(np.isfinite(arr)) or np.any(arr < 0.0):
        raise ValueError(f"{name} = {values!r} must be a non-empty 1-D sequence of finite >= 0")
    return arr


def _count(name: str, value: int, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name} = {value!r} must be an integer >= {minimum}")
    return int(value)


def _check_params(params: ScasParams) -> None:
    if not isinstance(params, ScasParams):
        raise ValueError(f"params must be a ScasParams, got {type(params).__name__}")


# ----------------------------------------------------------------------------- Fig. 3
@dataclass(frozen=True, eq=False)
class SpringRateCurves(_Curves):
    """Fig. 3: stiffness of the cracked spring and of its cracked coil against crack depth.

    Attributes
    ----------
    depth_m : crack depth grid a, 0 to the failure depth (m).
    spring_rate_exact_n_m, spring_rate_paper_n_m : spring rate K(a), eq. 1, with the exact
        polar moment and with the printed eq. 6 (N/m).
    coil_rate_exact_n_m, coil_rate_paper_n_m : cracked-coil rate K_f(a), eq. 5 (N/m).
    healthy_rate_n_m : G d^4 / (8 D^3 n) (N/m).
    failure_depth_m : min(brittle fracture, plastic collapse) depth (m).
    governing : which failure mode sets ``failure_depth_m``.
    """

    depth_m: FloatArray
    spring_rate_exact_n_m: FloatArray
    spring_rate_paper_n_m: FloatArray
    coil_rate_exact_n_m: FloatArray
    coil_rate_paper_n_m: FloatArray
    healthy_rate_n_m: float
    failure_depth_m: float
    governing: str


def fig3_spring_rate(params: ScasParams, *, n_points: int = 101) -> SpringRateCurves:
    """Spring and cracked-coil rates (eqs. 1, 5, 6) from a = 0 to the failure depth.

    1/K = (n - 1)/k_coil + 1/K_f(a), K_f = G (2C + 1) / (2 C^2 pi D (R r / J + 1/A)) with
    J(a) exact or as printed (ref §0.11); nominal spring geometry of ``params.spring``.
    """
    _check_params(params)
    n = _count("n_points", n_points, 2)
    s = params.spring
    fd = failure_depth_from_params(params)
    depth = np.linspace(0.0, fd.depth_m, n)
    coil = {
        form: coil_stiffness_n_per_m(
            depth,
            shear_modulus_pa=s.shear_modulus_pa,
            wire_diameter_m=s.wire_diameter_m,
            coil_diameter_m=s.mean_coil_diameter_m,
            j_form=form,
        )
        for form in ("exact", "paper")
    }
    return SpringRateCurves(
        depth_m=depth,
        spring_rate_exact_n_m=spring_rate_from_params(depth, s, "exact"),
        spring_rate_paper_n_m=spring_rate_from_params(depth, s, "paper"),
        coil_rate_exact_n_m=coil["exact"],
        coil_rate_paper_n_m=coil["paper"],
        healthy_rate_n_m=s.rate_n_per_m,
        failure_depth_m=fd.depth_m,
        governing=fd.governing,
    )


# ----------------------------------------------------------------------------- Fig. 4
@dataclass(frozen=True, eq=False)
class CrackGrowthCurves(_Curves):
    """Fig. 4: crack depth against flights, one row per Paris-C multiplier.

    Attributes
    ----------
    multipliers : growth multipliers theta = C_unit / C_nominal, shape (K,).
    flights : flights flown, row k evenly spaced from 0 to ``flights_to_failure[k]``, (K, N).
    depth_m : crack depth after ``flights`` (m), (K, N); the last column is the failure depth.
    flights_to_failure : flights from ``initial_depth_m`` to ``failure_depth_m``, (K,).
    initial_depth_m, failure_depth_m : start and end depth (m).
    dormant_below_m : depth below which no counted cycle passes the threshold (m).
    table_depth_m, table_rate_m_per_flight : the growth-rate table g(a) at theta = 1.
    """

    multipliers: FloatArray
    flights: FloatArray
    depth_m: FloatArray
    flights_to_failure: FloatArray
    initial_depth_m: float
    failure_depth_m: float
    dormant_below_m: float
    table_depth_m: FloatArray
    table_rate_m_per_flight: FloatArray


def crack_growth_curves(
    table: CrackRateTable,
    initial_depth_m: float,
    *,
    multipliers: Sequence[float] = DEFAULT_GROWTH_MULTIPLIERS,
    n_points: int = 200,
) -> CrackGrowthCurves:
    """Integrate da/dn = theta g(a) exactly on the piecewise-linear rate table.

    n_f(theta) = (I(a_f) - I(a0)) / theta and a(n) = I^-1(I(a0) + theta n) with the damage
    integral I(a) = int da / g(a) of :func:`prognostics.degradation_models.paris_crack_model`.
    ``initial_depth_m`` must lie in [table.depth_m[0], failure depth).
    """
    theta = _fractions("multipliers", multipliers)
    if np.any(theta <= 0.0):
        raise ValueError(f"multipliers = {multipliers!r} must all be > 0")
    n = _count("n_points", n_points, 2)
    a0, a_f = float(initial_depth_m), table.failure_depth_m
    if not (math.isfinite(a0) and table.depth_m[0] <= a0 < a_f):
        raise ValueError(
            f"initial_depth_m = {initial_depth_m} m must lie in [{table.depth_m[0]:.4g}, "
            f"{a_f:.4g}) m: from the smallest growing depth to the failure depth"
        )
    model = paris_crack_model(table.depth_m, table.rate_m_per_flight)
    i0, i_f = model.damage(np.array([a0, a_f]))
    n_fail = (i_f - i0) / theta
    flights = n_fail[:, None] * np.linspace(0.0, 1.0, n)[None, :]
    depth = model.inverse_damage(i0 + theta[:, None] * flights)
    depth[:, -1] = a_f  # the inverse of I(a_f) is a_f up to rounding
    return CrackGrowthCurves(
        multipliers=theta,
        flights=flights,
        depth_m=depth,
        flights_to_failure=n_fail,
        initial_depth_m=a0,
        failure_depth_m=a_f,
        dormant_below_m=table.dormant_below_m,
        table_depth_m=table.depth_m,
        table_rate_m_per_flight=table.rate_m_per_flight,
    )


def fig4_crack_growth(
    params: ScasParams,
    rng: np.random.Generator,
    *,
    window_s: float = 120.0,
    multipliers: Sequence[float] = DEFAULT_GROWTH_MULTIPLIERS,
    n_points: int = 200,
) -> CrackGrowthCurves:
    """Crack growth to failure from ``params.spring.initial_crack_m`` (paper Fig. 4).

    Loads: the Table-1 load spectrum simulated per regime for ``window_s`` each
    (:func:`scas_env.actuator.flight_damage.load_spectrum_from_physics`, noise on, draws from
    ``rng``),
    scaled to ``params.mission.flight_duration_s``; rate table from
    :func:`scas_env.actuator.flight_damage.crack_rate_table` (rainflow + Paris with threshold and
    Walker correction, force scaled with the cracked spring's rate k(a)).
    """
    _check_params(params)
    spectrum = load_spectrum_from_physics(params, rng, window_s=window_s)
    table = crack_rate_table(params, spectrum.per_flight(params.mission.flight_duration_s))
    return crack_growth_curves(
        table, params.spring.initial_crack_m, multipliers=multipliers, n_points=n_points
    )


# ----------------------------------------------------------------------------- Fig. 5
@dataclass(frozen=True, eq=False)
class FrequencyResponseCurves(_Curves):
    """Fig. 5: closed-loop responses at several wear levels and cut-off against leakage.

    Attributes
    ----------
    freq_hz : response frequencies (Hz), (F,).
    wear_m : seal wear of each response (m), (W,).
    magnitude_db, phase_deg : 20 log10 |X/X_cmd| (dB) and its unwrapped phase (deg), (W, F).
    sweep_wear_m : seal wear grid of the cut-off sweep (m), (S,).
    sweep_k_i1_m3_s_pa : laminar leakage coefficient K_i1 at each wear (m^3/(s Pa)), (S,).
    sweep_k_i2_m3_s_sqrtpa : orifice coefficient K_i2 (m^3/(s Pa^0.5)), 0 below the lip
        allowance, (S,).
    sweep_cutoff_hz : -3 dB cut-off frequency at each wear (Hz), (S,).
    healthy_cutoff_hz, critical_cutoff_hz : f_c of new seals and (1 - drop) f_c (Hz).
    critical_wear_m, critical_k_i1_m3_s_pa, critical_k_i2_m3_s_sqrtpa : the critical point.
    drop : relative cut-off drop that defines the critical wear (0.10).
    lip_wear_m : wear beyond which the damaged lip adds the orifice leakage K_i2 (m).
    """

    freq_hz: FloatArray
    wear_m: FloatArray
    magnitude_db: FloatArray
    phase_deg: FloatArray
    sweep_wear_m: FloatArray
    sweep_k_i1_m3_s_pa: FloatArray
    sweep_k_i2_m3_s_sqrtpa: FloatArray
    sweep_cutoff_hz: FloatArray
    healthy_cutoff_hz: float
    critical_cutoff_hz: float
    critical_wear_m: float
    critical_k_i1_m3_s_pa: float
    critical_k_i2_m3_s_sqrtpa: float
    drop: float
    lip_wear_m: float


def fig5_frequency_response(
    params: ScasParams,
    *,
    wear_fractions: Sequence[float] = DEFAULT_RESPONSE_WEAR_FRACTIONS,
    freq_range_hz: tuple[float, float] = (0.5, 50.0),
    n_freq: int = 25,
    sweep_max_fraction: float = 1.5,
    n_sweep: int = 13,
    criterion: SealCriterion | None = None,
) -> FrequencyResponseCurves:
    """Closed-loop responses and the cut-off vs leakage curve (paper Fig. 5).

    Responses: :func:`scas_env.actuator.bandwidth.closed_loop_gain` (nonlinear model, noise
    off, 0.2 mm sine) at ``n_freq`` log-spaced frequencies, at ``wear_fractions`` x the
    critical wear. Sweep: -3 dB cut-off (:func:`cutoff_frequency_hz`) at ``n_sweep`` wears
    evenly spaced from 0 to ``sweep_max_fraction`` x critical, with K_i1, K_i2 of eq. 9 at
    the nominal fluid temperature. ``criterion`` (default: :func:`seal_criterion`) gives the
    critical wear lambda_c where f_c = 0.9 f_c(0).
    """
    _check_params(params)
    fractions = _fractions("wear_fractions", wear_fractions)
    f_lo, f_hi = (float(f) for f in freq_range_hz)
    if not (0.0 < f_lo < f_hi and math.isfinite(f_hi)):
        raise ValueError(f"freq_range_hz = {freq_range_hz!r} must satisfy 0 < low < high")
    n_f = _count("n_freq", n_freq, 2)
    n_s = _count("n_sweep", n_sweep, 2)
    if not (math.isfinite(sweep_max_fraction) and sweep_max_fraction > 0.0):
        raise ValueError(f"sweep_max_fraction = {sweep_max_fraction} must be finite and > 0")
    crit = seal_criterion(params) if criterion is None else criterion
    freq = np.geomspace(f_lo, f_hi, n_f)
    wear = fractions * crit.critical_wear_m
    gains = np.array(
        [
            [
                closed_loop_gain(actuator_config(params, health=HealthState(seal_wear_m=w)), f)
                for f in freq
            ]
            for w in wear
        ]
    )
    sweep_wear = np.linspace(0.0, sweep_max_fraction, n_s) * crit.critical_wear_m
    temp = params.fluid.temperature_c
    leak = np.array([leakage_at(params, w, temp) for w in sweep_wear])
    cutoff = np.array([cutoff_frequency_hz(params, HealthState(seal_wear_m=w)) for w in sweep_wear])
    k1_c, k2_c = leakage_at(params, crit.critical_wear_m, temp)
    return FrequencyResponseCurves(
        freq_hz=freq,
        wear_m=wear,
        magnitude_db=20.0 * np.log10(np.abs(gains)),
        phase_deg=np.degrees(np.unwrap(np.angle(gains), axis=1)),
        sweep_wear_m=sweep_wear,
        sweep_k_i1_m3_s_pa=leak[:, 0],
        sweep_k_i2_m3_s_sqrtpa=leak[:, 1],
        sweep_cutoff_hz=cutoff,
        healthy_cutoff_hz=crit.healthy_cutoff_hz,
        critical_cutoff_hz=crit.critical_cutoff_hz,
        critical_wear_m=crit.critical_wear_m,
        critical_k_i1_m3_s_pa=k1_c,
        critical_k_i2_m3_s_sqrtpa=k2_c,
        drop=crit.drop,
        lip_wear_m=params.seal.lip_wear_m,
    )


# --------------------------------------------------------------------- Fig. 7a and 7b
def _preflight_run(params: ScasParams, profile: MissionProfile, health: HealthState) -> ActuatorRun:
    """Noise-free pre-flight test of the nominal unit at ``health``."""
    return simulate(
        actuator_config(params, health=health), profile.scas_command_m, rng=None, noise=False
    )


def zero_plateau_current_a(
    run: ActuatorRun, profile: MissionProfile, *, settle_fraction: float = 0.5
) -> float:
    """Null-bias current: mean current over the settled part of the test's zero plateaus (A).

    Each plateau at level 0 of the pre-flight test contributes its samples after the first
    ``settle_fraction`` of the dwell (the step transient has died out by mid-dwell:
    the loop time constant is ~16 ms against a 0.5 s dwell).
    """
    if not (math.isfinite(settle_fraction) and 0.0 <= settle_fraction < 1.0):
        raise ValueError(f"settle_fraction = {settle_fraction} must lie in [0, 1)")
    if run.current_a.size != profile.n_samples:
        raise ValueError(
            f"run has {run.current_a.size} samples but the profile {profile.n_samples}"
        )
    parts = []
    for step in profile.steps:
        if step.level_m == 0.0:
            first = step.start_index + int(settle_fraction * (step.stop_index - step.start_index))
            parts.append(run.current_a[first : step.stop_index])
    if not parts:
        raise ValueError("the profile has no zero-level plateau (is it a pre-flight test?)")
    return float(np.mean(np.concatenate(parts)))


@dataclass(frozen=True, eq=False)
class NullBiasCurves(_Curves):
    """Fig. 7a: servovalve current with a cracked centering spring.

    Attributes
    ----------
    t_s, command_m : pre-flight test time (s) and SCAS command (m), (N,).
    trace_depth_m : crack depth of each trace (m), (K,).
    current_a : recorded servovalve current, noise off (A), (K, N).
    depth_m : crack depth grid of the null-bias curve (m), (M,).
    null_bias_a : mean current on the settled zero plateaus (A), (M,).
    failure_depth_m : failure depth of the spring (m).
    """

    t_s: FloatArray
    command_m: FloatArray
    trace_depth_m: FloatArray
    current_a: FloatArray
    depth_m: FloatArray
    null_bias_a: FloatArray
    failure_depth_m: float


def fig7a_null_bias(
    params: ScasParams,
    *,
    trace_fractions: Sequence[float] = DEFAULT_TRACE_DEPTH_FRACTIONS,
    n_depths: int = 11,
) -> NullBiasCurves:
    """Pre-flight test currents for several crack depths and null bias vs depth (Fig. 7a).

    Depths are fractions of the failure depth; the null-bias grid is ``n_depths`` depths
    evenly spaced from 0 to the failure depth (:func:`zero_plateau_current_a`).
    """
    _check_params(params)
    fractions = _fractions("trace_fractions", trace_fractions)
    n_d = _count("n_depths", n_depths, 2)
    a_f = failure_depth_from_params(params).depth_m
    if np.any(fractions * a_f >= params.spring.wire_diameter_m):
        raise ValueError(f"trace_fractions = {trace_fractions!r} reach the wire diameter")
    profile = preflight_test_command(params.mission, params.sensors.sample_rate_hz)
    trace_depth = fractions * a_f
    traces = [_preflight_run(params, profile, HealthState(crack_depth_m=a)) for a in trace_depth]
    depth = np.linspace(0.0, a_f, n_d)
    bias = [
        zero_plateau_current_a(
            _preflight_run(params, profile, HealthState(crack_depth_m=a)), profile
        )
        for a in depth
    ]
    return NullBiasCurves(
        t_s=profile.t_s,
        command_m=profile.scas_command_m,
        trace_depth_m=trace_depth,
        current_a=np.stack([r.current_a for r in traces]),
        depth_m=depth,
        null_bias_a=bias,
        failure_depth_m=a_f,
    )


@dataclass(frozen=True, eq=False)
class SealGainCurves(_Curves):
    """Fig. 7b: servovalve current and position with worn seals, servo gain against wear.

    Attributes
    ----------
    t_s, command_m : pre-flight test time (s) and SCAS command (m), (N,).
    trace_wear_m : seal wear of each trace (m), (K,).
    current_a, position_m : recorded current (A) and true position (m), noise off, (K, N).
    wear_m : wear grid of the gain curve (m), (M,).
    gain : |X/X_cmd| at ``gain_frequency_hz`` (-), (M,).
    gain_frequency_hz : frequency of the gain (Hz).
    critical_wear_m : wear at which the cut-off has dropped by 10% (m).
    """

    t_s: FloatArray
    command_m: FloatArray
    trace_wear_m: FloatArray
    current_a: FloatArray
    position_m: FloatArray
    wear_m: FloatArray
    gain: FloatArray
    gain_frequency_hz: float
    critical_wear_m: float


def fig7b_seal_gain(
    params: ScasParams,
    *,
    trace_fractions: Sequence[float] = DEFAULT_TRACE_WEAR_FRACTIONS,
    n_wear: int = 11,
    max_fraction: float = 2.0,
    gain_frequency_hz: float = GAIN_FREQUENCY_HZ,
    criterion: SealCriterion | None = None,
) -> SealGainCurves:
    """Pre-flight test signals for several wear levels and servo gain vs wear (Fig. 7b).

    Wear levels are fractions of the critical wear (``criterion``, default
    :func:`seal_criterion`); the gain grid is ``n_wear`` wears from 0 to ``max_fraction`` x
    critical, gain = |:func:`closed_loop_gain`| at ``gain_frequency_hz``.
    """
    _check_params(params)
    fractions = _fractions("trace_fractions", trace_fractions)
    n_w = _count("n_wear", n_wear, 2)
    if not (math.isfinite(max_fraction) and max_fraction > 0.0):
        raise ValueError(f"max_fraction = {max_fraction} must be finite and > 0")
    crit = seal_criterion(params) if criterion is None else criterion
    profile = preflight_test_command(params.mission, params.sensors.sample_rate_hz)
    trace_wear = fractions * crit.critical_wear_m
    traces = [_preflight_run(params, profile, HealthState(seal_wear_m=w)) for w in trace_wear]
    wear = np.linspace(0.0, max_fraction, n_w) * crit.critical_wear_m
    gain = [
        abs(
            closed_loop_gain(
                actuator_config(params, health=HealthState(seal_wear_m=w)), gain_frequency_hz
            )
        )
        for w in wear
    ]
    return SealGainCurves(
        t_s=profile.t_s,
        command_m=profile.scas_command_m,
        trace_wear_m=trace_wear,
        current_a=np.stack([r.current_a for r in traces]),
        position_m=np.stack([r.position_m for r in traces]),
        wear_m=wear,
        gain=gain,
        gain_frequency_hz=float(gain_frequency_hz),
        critical_wear_m=crit.critical_wear_m,
    )


# ------------------------------------------------------------------------ all figures
@dataclass(frozen=True, eq=False)
class PaperFigures:
    """The data of every physics figure of the paper."""

    fig3: SpringRateCurves
    fig4: CrackGrowthCurves
    fig5: FrequencyResponseCurves
    fig7a: NullBiasCurves
    fig7b: SealGainCurves

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Figure name -> the figure's ``to_dict()``."""
        return {f.name: getattr(self, f.name).to_dict() for f in fields(self)}


def paper_figures(params: ScasParams, rng: np.random.Generator) -> PaperFigures:
    """Compute Figs. 3, 4, 5, 7a, 7b with their defaults (``rng`` drives the Fig. 4 loads)."""
    _check_params(params)
    crit = seal_criterion(params)
    return PaperFigures(
        fig3=fig3_spring_rate(params),
        fig4=fig4_crack_growth(params, rng),
        fig5=fig5_frequency_response(params, criterion=crit),
        fig7a=fig7a_null_bias(params),
        fig7b=fig7b_seal_gain(params, criterion=crit),
    )
