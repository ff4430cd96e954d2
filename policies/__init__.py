"""Maintenance policies (rules, oracle, random) and the policy benchmark.

Importing the package registers every built-in policy by name (:func:`make_policy`).
"""

from policies.base import (
    POLICIES,
    Policy,
    make_policy,
    policy_family,
    policy_obs_mode,
    register_policy,
)
from policies.rules import fleet as _fleet  # noqa: F401  (registers the fleet rules)
from policies.rules import fleet_bound as _fleet_bound  # noqa: F401  (and the fleet's bound)
from policies.rules.classic import (
    CorrectivePolicy,
    DetectionPolicy,
    PreventivePolicy,
    RandomPolicy,
)
from policies.rules.noisy_oracle import NoisyOraclePolicy
from policies.rules.oracle import OraclePolicy
from policies.rules.prognostic import FeatureRulePolicy, RulRiskPolicy

__all__ = [
    "POLICIES",
    "CorrectivePolicy",
    "DetectionPolicy",
    "FeatureRulePolicy",
    "NoisyOraclePolicy",
    "OraclePolicy",
    "Policy",
    "PreventivePolicy",
    "RandomPolicy",
    "RulRiskPolicy",
    "make_policy",
    "policy_family",
    "policy_obs_mode",
    "register_policy",
]
