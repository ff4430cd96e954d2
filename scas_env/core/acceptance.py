"""The pre-flight test's go/no-go: an airworthiness limit.

The test fails when a ground feature has moved, since the installation's own reference, by
as much as an actuator whose part has reached its critical level (the level at which it no
longer meets its function: spring fracture, [DJS20] eq. 7; a 10 % loss of closed-loop
bandwidth for the seals, Fig. 5). It is not a detector's alarm band: a part short of its
critical level is fit to fly and should pass.

At fitting, a maintainer records the installation's reference
reading of each ground feature, the mean of ``reference_tests`` tests of the healthy
installation (:func:`scas_env.core.parts.record_reference`); the spring-pair and installation
tolerances then cancel. The deviation ``d_f = G_f - ref_f`` of feature ``f`` at crack and
wear fractions ``(c, w)`` is normal with (surrogate tables: mean ``m``, unit ``u`` and run
``r`` spreads; ``z`` the installation's standardised effect)

    E[d_f] = m_f(c, w) - m_f(0, 0),  Var[d_f] = (u_f(c, w) - u_f(0, 0))^2 + r_f(c, w)^2
                                                 + r_f(0, 0)^2 / reference_tests.

Each ground feature watches the part it responds to (G1, the null-bias current: the spring;
G3 = i/x: the seals, [DJS20] §5.1). Its limit ``L_f`` is the ``1 - acceptance_catch``
quantile of ``|d_f|`` at that part's critical level (the other part new), so a part at its
critical level fails the test with probability ``acceptance_catch`` (0.9 by default); the
test fails when any ``|d_f| > L_f``. A healthy actuator then fails it with the probability
:meth:`AirworthinessLimits.no_go_probability` gives at ``(0, 0)``, measured, not chosen.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from scipy.optimize import brentq
from scipy.stats import norm

from scas_env.actuator.surrogate import SurrogateModel

#: ground feature -> the part whose critical level sets its limit (crack / wear axis)
WATCHED_PART = {"G1": "spring", "G3": "seal"}


def _deviation(
    surrogate: SurrogateModel, feature: str, crack: float, wear: float, reference_tests: int
) -> tuple[float, float]:
    """Mean and sd of ``G_f - ref_f`` at crack and wear fractions (module docstring)."""
    k = surrogate.index(feature)
    at, healthy = surrogate.tables_at(crack, wear), surrogate.tables_at(0.0, 0.0)
    mean = float(at[0, k] - healthy[0, k])
    var = (at[1, k] - healthy[1, k]) ** 2 + at[2, k] ** 2 + healthy[2, k] ** 2 / reference_tests
    return mean, math.sqrt(float(var))


def _p_outside(mean: float, sd: float, limit: float) -> float:
    """P(|N(mean, sd^2)| > limit)."""
    return float(norm.sf((limit - mean) / sd) + norm.cdf((-limit - mean) / sd))


@dataclass(frozen=True)
class AirworthinessLimits:
    """Limits on the ground features' deviation from the installation reference.

    Attributes
    ----------
    limits : feature -> limit on ``|G_f - ref_f|`` (SI units of the feature: A, A/m).
    reference_tests : tests averaged into the installation reference.
    """

    surrogate: SurrogateModel
    limits: Mapping[str, float]
    reference_tests: int

    @classmethod
    def from_surrogate(
        cls, surrogate: SurrogateModel, *, reference_tests: int, catch: float
    ) -> AirworthinessLimits:
        """Limits that ground a part at its critical level with probability ``catch``."""
        if not 0.5 <= catch < 1.0:
            raise ValueError(f"catch = {catch!r} must lie in [0.5, 1)")
        if reference_tests < 1:
            raise ValueError(f"reference_tests = {reference_tests!r} must be >= 1")
        limits = {}
        for feature, part in WATCHED_PART.items():
            crack, wear = (1.0, 0.0) if part == "spring" else (0.0, 1.0)
            mean, sd = _deviation(surrogate, feature, crack, wear, reference_tests)
            # the 1 - catch quantile of |d| at critical: P(|d| > L) = catch
            hi = abs(mean) + 10.0 * sd
            limits[feature] = brentq(lambda x, m=mean, s=sd: _p_outside(m, s, x) - catch, 0.0, hi)
        return cls(surrogate, limits, int(reference_tests))

    def passes(self, features: Mapping[str, float], reference: Mapping[str, float]) -> bool:
        """Go: every watched ground feature within its limit of the reference."""
        return all(abs(features[f] - reference[f]) <= lim for f, lim in self.limits.items())

    def no_go_probability(self, crack_fraction: float, wear_fraction: float) -> float:
        """P(the test fails) at the given severities (fractions of critical, in [0, 1]),
        the features' deviations taken as independent normals (module docstring)."""
        p_pass = 1.0
        for feature, limit in self.limits.items():
            mean, sd = _deviation(
                self.surrogate, feature, crack_fraction, wear_fraction, self.reference_tests
            )
            p_pass *= 1.0 - _p_outside(mean, sd, limit)
        return 1.0 - p_pass


__all__ = ["WATCHED_PART", "AirworthinessLimits"]
