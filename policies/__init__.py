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
from policies.noisy_oracle import NoisyOraclePolicy
from policies.oracle import OraclePolicy
from policies.prognostic import FeatureRulePolicy, RulRiskPolicy
from policies.rules import (
    CorrectivePolicy,
    DetectionPolicy,
    PreventivePolicy,
    RandomPolicy,
)

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
