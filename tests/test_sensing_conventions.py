"""The paper's conventions (leakage fraction, G2) and the sensing presets."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.paper.reproduction_conventions import (
    EXCLUDED_FEATURES,
    g2_noise_check,
    leakage_fraction,
)
from scas_env.actuator.calibration import default_calibration
from scas_env.actuator.params import ScasParams
from scas_env.actuator.physics.seal import laminar_leakage_coeff_m3_s_pa
from scas_env.actuator.presets import PRESETS, preset_params

P = ScasParams()
CAL = default_calibration()


def test_leakage_fraction_is_the_laminar_coefficient_growth_of_the_seal_model() -> None:
    # independent route: the physics' K_i1(lambda), at any viscosity (it cancels)
    lam_c = CAL.seal_critical_wear_m
    f = np.array([0.0, 0.1, 0.25, 0.51, 0.61, 1.0, 1.2])
    k = laminar_leakage_coeff_m3_s_pa(f * lam_c, P.seal, 0.012)
    k0, kc = laminar_leakage_coeff_m3_s_pa(np.array([0.0, lam_c]), P.seal, 0.012)
    np.testing.assert_allclose(leakage_fraction(f, P.seal, lam_c), (k - k0) / (kc - k0), rtol=1e-12)
    # a path that never detects stays NaN
    assert np.isnan(leakage_fraction(np.nan, P.seal, lam_c))


def test_leakage_fraction_refuses_bad_input() -> None:
    with pytest.raises(ValueError, match="critical_wear_m"):
        leakage_fraction(0.5, P.seal, 0.0)
    with pytest.raises(ValueError, match="wear_fraction"):
        leakage_fraction(-0.1, P.seal, 1e-5)
    with pytest.raises(ValueError, match="wear_fraction"):
        leakage_fraction(np.inf, P.seal, 1e-5)


def test_g2_reads_lvdt_noise_not_an_overshoot() -> None:
    out = g2_noise_check(P, CAL.seal_critical_wear_m, CAL.spring_failure_depth_m, 12, 3)
    for state, row in out.items():
        # no overshoot in any state: every noise-free plateau ends short of its set-point
        assert row["noise_free"] < 0.0, state
        # the noisy value sits above the noise-free one by the noise maximum, and its
        # spread is the LVDT's: it collapses when the LVDT noise alone is switched off
        assert row["noisy_mean"] > row["noise_free"] + 5 * row["noisy_sd"], state
        assert row["no_lvdt_noise_sd"] < row["noisy_sd"] / 3.0, state
    assert "G2" in EXCLUDED_FEATURES and "overshoot" in EXCLUDED_FEATURES["G2"]


def test_realistic_preset_is_the_default_parameters() -> None:
    assert preset_params("realistic").to_dict() == P.to_dict()


def test_paper_preset_applies_each_override_and_nothing_else() -> None:
    paper = preset_params("paper")
    changed = {
        (group, name)
        for group, values in paper.to_dict().items()
        for name, value in values.items()
        if P.to_dict()[group][name] != value
    }
    overrides = {(o.group, o.name): o for o in PRESETS["paper"]}
    assert changed == set(overrides)
    for (group, name), o in overrides.items():
        assert getattr(getattr(paper, group), name) == o.value
        assert len(o.reason) > 20  # every assumption carries its reason
    # the steps stay inside the end stops and the current below its limit
    assert paper.mission.test_step_m < paper.actuator.end_stop_m
    step_current = paper.controller.kp_a_per_m * paper.mission.test_step_m
    assert step_current < paper.controller.current_limit_a


def test_unknown_preset_is_refused() -> None:
    with pytest.raises(ValueError, match="preset = 'nope'"):
        preset_params("nope")


def _report(ours: str, verdict: str, claim: str = "seal wear: severity at detection") -> dict:
    row = {"claim": claim, "paper": 0.09, "ours": ours, "verdict": verdict}
    return {"verdicts": [{**row, "ours_worn_depth": "prognosis 0.51"}]}


def test_preset_table_has_a_column_per_preset(tmp_path) -> None:
    import json

    from experiments.paper.reproduction_presets import preset_table, read_reports

    paths = {}
    for name, ours, verdict in (("realistic", "0.27", "differs"), ("paper", "0.10", "holds")):
        paths[name] = tmp_path / f"{name}.json"
        paths[name].write_text(json.dumps(_report(ours, verdict)))
    lines = preset_table(read_reports(paths)).splitlines()
    assert (
        lines[0] == "| result | paper | realistic | realistic: verdict | paper | paper: verdict |"
    )
    assert lines[2] == (
        "| seal wear: severity at detection | 0.09 | 0.27 [worn depth: prognosis 0.51] | "
        "differs | 0.10 [worn depth: prognosis 0.51] | holds |"
    )
    paths["other"] = tmp_path / "other.json"
    paths["other"].write_text(json.dumps(_report("x", "holds", claim="another claim")))
    with pytest.raises(ValueError, match="different claims"):
        read_reports(paths)
