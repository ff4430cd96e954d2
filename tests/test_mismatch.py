"""Model mismatch (scas_env.core.mismatch): each knob moves the world's constant it names and
only that; the monitor's model (filters, detectors, go/no-go limits) never moves.

Independent computations: the surrogate's own numpy path (``SurrogateModel.tables_at``) for
the features, the nominal growth table's numpy ``damage`` for a flight's crack growth, the
lognormal scatter written out in numpy, and the unit draws' log-normal law.
"""

from __future__ import annotations

import math
from dataclasses import fields

import gymnasium as gym
import numpy as np
import pytest

import scas_env
from prognostics.degradation_models import paris_crack_model
from scas_env.actuator.calibration import default_calibration
from scas_env.actuator.config import FILE_SECTIONS, save_sections
from scas_env.actuator.surrogate import default_surrogate
from scas_env.core.costs import CostModel
from scas_env.core.flight import crack_after_flight, wear_after_flight
from scas_env.core.mismatch import GROWTH_FIELDS, SENSING_FIELDS, Mismatch
from scas_env.core.scenario import Scenario
from scas_env.core.setup import FLIGHT_FEATURES, lognormal_sigma
from scas_env.env import make_setup

ENV_ID = scas_env.ENV_ID


def _setup(mismatch: Mismatch | None = None, **scenario):
    return make_setup(None, None, None, None, None, scenario, mismatch)


def _same(a, b) -> bool:
    """Equal, bit for bit, through tuples and named tuples of arrays and scalars."""
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    return type(a) is type(b) and (a == b or (a != a and b != b))


# --------------------------------------------------------------------------- the config
def test_defaults_are_no_mismatch_and_every_field_is_a_documented_multiplier() -> None:
    m = Mismatch()
    assert m.is_nominal and m.changed() == {}
    assert {f.name for f in fields(Mismatch)} == set(GROWTH_FIELDS) | set(SENSING_FIELDS)
    for name, default, unit, _, source in Mismatch.describe():
        assert (default, unit) == (1.0, "-") and source, name


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"crack_grwoth": 1.2}, r"Mismatch: unknown key\(s\) \['crack_grwoth'\]"),
        ({"sensing_noise": 0.0}, r"Mismatch\.sensing_noise = 0\.0 - is outside"),
        ({"wear_growth": -1.0}, r"Mismatch\.wear_growth = -1\.0 - is outside"),
        ({"crack_unit_scatter": 11.0}, r"Mismatch\.crack_unit_scatter = 11\.0 - is outside"),
        ({"installation_spread": math.nan}, r"installation_spread = nan - is not finite"),
        ({"crack_growth": True}, r"Mismatch\.crack_growth = True is a boolean"),
        ({"crack_growth": "fast"}, r"Mismatch\.crack_growth = 'fast' is not a number"),
    ],
)
def test_bad_values_and_unknown_keys_are_refused(data, message) -> None:
    with pytest.raises(ValueError, match=message):
        Mismatch.from_dict(data)


def test_a_case_file_holds_a_mismatch_table_beside_the_scenario(tmp_path) -> None:
    assert FILE_SECTIONS["mismatch"] == "Mismatch"
    case = {
        "scenario": Scenario(episode_slots=300),
        "costs": CostModel(test_usd=50.0),
        "mismatch": Mismatch(crack_growth=1.3, sensing_noise=2.0),
    }
    for suffix in (".toml", ".yaml", ".json"):
        path = save_sections(tmp_path / f"case{suffix}", case)
        assert Mismatch.load(path) == case["mismatch"]
        assert Scenario.load(path) == case["scenario"]
    bad = tmp_path / "bad.toml"
    bad.write_text("[scenario]\nepisode_slots = 30\n\n[mismatch]\nnoise = 2.0\n")
    with pytest.raises(ValueError, match=r"bad\.toml \[mismatch\]: Mismatch: unknown key"):
        Mismatch.load(bad)
    only = tmp_path / "only.toml"
    only.write_text("[scenario]\nepisode_slots = 30\n")
    with pytest.raises(ValueError, match=r"no \[mismatch\] table for Mismatch"):
        Mismatch.load(only)


def test_env_keyword_is_checked_and_physics_refuses_the_sensing_knobs() -> None:
    with pytest.raises(ValueError, match=r"mismatch = .* must be None .* or a Mismatch"):
        gym.make(ENV_ID, mismatch={"crack_growth": 1.2})
    for name in SENSING_FIELDS:
        with pytest.raises(ValueError, match="surrogate fidelity only"):
            _setup(Mismatch(**{name: 2.0}), fidelity="physics")
    _setup(Mismatch(crack_growth=1.2, wear_unit_scatter=2.0), fidelity="physics")


# --------------------------------------------------------------------------- the setup
KNOBS = {name: 1.7 for name in (*GROWTH_FIELDS, *SENSING_FIELDS)}


def test_no_mismatch_keeps_the_nominal_objects() -> None:
    st = _setup()
    assert st.world_params is st.params and st.world_features is st.surrogate


@pytest.mark.parametrize("name", list(KNOBS))
def test_the_monitor_keeps_the_nominal_model(name: str) -> None:
    """Filters, detectors, go/no-go limits and the filters' priors: bit for bit nominal."""
    nominal, st = _setup(), _setup(Mismatch(**{name: KNOBS[name]}))
    for f in nominal.filters._fields:
        assert _same(getattr(st.filters, f), getattr(nominal.filters, f)), f
    for f in nominal.detector._fields:
        assert _same(getattr(st.detector, f), getattr(nominal.detector, f)), f
    assert _same(st.go_limits, nominal.go_limits)
    assert st.limits.limits == nominal.limits.limits
    assert st.params == nominal.params and st.surrogate is nominal.surrogate
    for part in ("spring", "seal"):
        assert lognormal_sigma(st.params, part) == lognormal_sigma(nominal.params, part)


#: the world's fields each knob may move (WorldModel fields; "params"/"surrogate": the
#: world's unit draws and feature tables)
MOVES = {
    "crack_growth": {"damage", "type_rate", "type_cum"},
    "wear_growth": {"wear_rate_m"},
    "crack_unit_scatter": {"params"},
    "wear_unit_scatter": {"params"},
    "crack_flight_scatter": {"cv_values", "type_cv"},
    "wear_flight_scatter": {"wear_cv", "type_wear_cv"},
    "sensing_noise": {"stack", "surrogate"},
    "installation_spread": {"stack", "surrogate"},
}


@pytest.mark.parametrize("name", list(KNOBS))
def test_each_knob_moves_only_its_own_world_constants(name: str) -> None:
    nominal, st = _setup(), _setup(Mismatch(**{name: KNOBS[name]}))
    moved = {
        f
        for f in nominal.world._fields
        if not _same(getattr(st.world, f), getattr(nominal.world, f))
    }
    if st.world_params != nominal.params:
        moved.add("params")
    if st.world_features is not nominal.surrogate:
        moved.add("surrogate")
    assert moved == MOVES[name]


def test_growth_multiplier_scales_the_damage_of_a_flight() -> None:
    """One flight from depth a with multiplier theta and draw z: the nominal table's damage
    (numpy) grows by g * theta * (lognormal factor of the calibration's CV at a)."""
    cal = default_calibration()
    g = 1.37
    wm = _setup(Mismatch(crack_growth=g)).world
    nominal_table = paris_crack_model(cal.crack_depth_m, cal.crack_rate_m_per_flight)
    cv_depth = np.log(cal.crack_cv_depth_m)
    cv_values = np.asarray(cal.flight_scatter("whole_flight")[0])
    for a, theta, z in ((2e-4, 1.0, 0.0), (4e-4, 0.8, 1.3), (9e-4, 1.6, -0.7)):
        after = crack_after_flight(
            a, theta, z, 1.0, *wm.damage, wm.cv_log_depth, wm.cv_values, wm.dormant_m
        )
        cv = float(np.interp(np.log(a), cv_depth, cv_values))
        s2 = np.log1p(cv * cv)
        factor = np.exp(np.sqrt(s2) * z - 0.5 * s2)
        gained = nominal_table.damage(np.array([after]))[0] - nominal_table.damage(np.array([a]))[0]
        assert gained == pytest.approx(g * theta * factor, rel=1e-9)


def test_wear_multiplier_scales_the_wear_of_a_flight_and_flight_scatter_its_cv() -> None:
    cal = default_calibration()
    nominal_cv = cal.flight_scatter("whole_flight")[1]
    wm = _setup(Mismatch(wear_growth=0.8, wear_flight_scatter=4.0)).world
    assert wm.wear_rate_m == 0.8 * cal.wear_rate_m_per_flight
    assert wm.wear_cv == 4.0 * nominal_cv
    z, mult = 0.9, 1.1
    s2 = np.log1p((4.0 * nominal_cv) ** 2)
    expected = 0.8 * cal.wear_rate_m_per_flight * mult * np.exp(np.sqrt(s2) * z - 0.5 * s2)
    got = wear_after_flight(1e-5, wm.wear_rate_m * mult, wm.wear_cv, z, 1.0) - 1e-5
    assert got == pytest.approx(expected, rel=1e-12, abs=0.0)


def test_growth_multipliers_scale_every_mission_type() -> None:
    types = ("standard", "training", "offshore_gusts")
    nominal = _setup().__class__  # Setup
    base = _setup()
    kw = {
        "params": base.params,
        "scenario": base.scenario,
        "costs": base.costs,
        "calibration": base.calibration,
        "surrogate": base.surrogate,
        "mission_types": types,
    }
    st0 = nominal(**kw)
    st = nominal(**kw, mismatch=Mismatch(crack_growth=2.0, crack_flight_scatter=3.0))
    for k in range(len(types)):
        np.testing.assert_allclose(st.world.type_cum[k], st0.world.type_cum[k] / 2.0, rtol=1e-12)
        np.testing.assert_allclose(st.world.type_cv[k], 3.0 * st0.world.type_cv[k], rtol=0)
    assert _same(st.world.type_crack_mult, st0.world.type_crack_mult)  # the filters' usage


# --------------------------------------------------------------------------- episodes
def _reset(mismatch: Mismatch | None, seed: int = 3, **scenario):
    env = gym.make(ENV_ID, mismatch=mismatch, **scenario)
    _, info = env.reset(seed=seed)
    return env, info


def test_unit_scatter_multiplies_the_log_of_each_drawn_growth_constant() -> None:
    """Same seed: the same standard normals, so log(theta) and log(wmult) scale by k."""
    for seed in range(4):
        e1, _ = _reset(None, seed)
        ek, _ = _reset(Mismatch(crack_unit_scatter=2.5, wear_unit_scatter=0.5), seed)
        a1, ak = e1.unwrapped.batch.a, ek.unwrapped.batch.a
        assert math.log(ak["theta"][0]) == pytest.approx(2.5 * math.log(a1["theta"][0]), rel=1e-12)
        assert math.log(ak["wmult"][0]) == pytest.approx(0.5 * math.log(a1["wmult"][0]), rel=1e-12)
        assert ak["crack"][0] == a1["crack"][0]  # the initial flaw is not a growth constant


def test_growth_multipliers_shorten_the_lives_and_scale_the_wear() -> None:
    """Same seed: the seals' wear after n flights is exactly g times the nominal (a sum of
    rate * multiplier * factor); every drawn life shrinks by about 1/g."""
    e1, i1 = _reset(None, 5)
    eg, ig = _reset(Mismatch(crack_growth=1.25, wear_growth=1.25), 5)
    for _ in range(60):
        *_, i1 = e1.step(0)
        *_, ig = eg.step(0)
    assert ig["true_state"]["seal_wear_m"] == pytest.approx(
        1.25 * i1["true_state"]["seal_wear_m"], rel=1e-12, abs=0.0
    )
    lives = np.array(
        [
            [_reset(m, s)[1]["true_state"][f"{p}_rul_flights"] for p in ("spring", "seal")]
            for m in (None, Mismatch(crack_growth=1.25, wear_growth=1.25))
            for s in range(6)
        ]
    ).reshape(2, 6, 2)
    np.testing.assert_allclose(lives[1] / lives[0], 0.8, rtol=0.02)


def _first_flight(mismatch: Mismatch | None, seed: int = 11):
    env, info = _reset(mismatch, seed)
    c, w = info["true_state"]["crack_fraction"], info["true_state"]["wear_fraction"]
    *_, after = env.step(0)
    a = env.unwrapped.batch.a
    feats = np.array([after["features"][f] for f in FLIGHT_FEATURES])
    return c, w, a["unit_z"][0].copy(), feats, a["reference"][0].copy()


def _tables(surrogate, c, w, names):
    t = surrogate.tables_at(c, w)
    idx = [surrogate.index(f) for f in names]
    return t[0, idx], t[1, idx], t[2, idx]


def test_sensing_noise_scales_the_run_noise_of_the_features_and_the_reference() -> None:
    """Same seed, same state and installation: feature minus its installation's mean (from the
    surrogate's numpy tables) is k times the nominal one, in flight and in the reference tests."""
    sur, k = default_surrogate(), 2.5
    c, w, uz, f1, ref1 = _first_flight(None)
    ck, wk, uzk, fk, refk = _first_flight(Mismatch(sensing_noise=k))
    assert (c, w) == (ck, wk) and np.array_equal(uz, uzk)
    mean, unit, _ = _tables(sur, c, w, FLIGHT_FEATURES)
    centre = mean + unit * uz[[sur.index(f) for f in FLIGHT_FEATURES]]
    np.testing.assert_allclose(fk - centre, k * (f1 - centre), rtol=1e-9, atol=1e-12)
    mean0, unit0, _ = _tables(sur, 0.0, 0.0, ("G1", "G3"))
    centre0 = mean0 + unit0 * uz[[sur.index("G1"), sur.index("G3")]]
    np.testing.assert_allclose(refk - centre0, k * (ref1 - centre0), rtol=1e-9, atol=1e-15)


def test_installation_spread_scales_the_installation_effect_of_the_features() -> None:
    """f_k - f_1 = (k - 1) * unit_std(c, w) * z_unit, the run noise unchanged."""
    sur, k = default_surrogate(), 3.0
    c, w, uz, f1, ref1 = _first_flight(None)
    _, _, _, fk, refk = _first_flight(Mismatch(installation_spread=k))
    _, unit, _ = _tables(sur, c, w, FLIGHT_FEATURES)
    z = uz[[sur.index(f) for f in FLIGHT_FEATURES]]
    np.testing.assert_allclose(fk - f1, (k - 1.0) * unit * z, rtol=1e-9, atol=1e-12)
    _, unit0, _ = _tables(sur, 0.0, 0.0, ("G1", "G3"))
    z0 = uz[[sur.index("G1"), sur.index("G3")]]
    np.testing.assert_allclose(refk - ref1, (k - 1.0) * unit0 * z0, rtol=1e-9, atol=1e-15)


def test_the_vector_env_runs_the_same_mismatched_episodes_as_single_envs() -> None:
    m = Mismatch(crack_growth=1.4, sensing_noise=2.0, wear_unit_scatter=1.5)
    n, steps = 3, 150
    rng = np.random.default_rng(0)
    actions = rng.choice(4, size=(steps, n), p=[0.85, 0.1, 0.025, 0.025])
    venv = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point", mismatch=m)
    obs, _ = venv.reset(seed=[10, 11, 12])
    vec = [obs]
    for t in range(steps):
        obs, *_ = venv.step(actions[t])
        vec.append(obs)
    for e in range(n):
        env = gym.make(ENV_ID, mismatch=m)
        obs, _ = env.reset(seed=10 + e)
        assert np.array_equal(obs, vec[0][e])
        for t in range(steps):
            obs, *_ = env.step(int(actions[t, e]))
            assert np.array_equal(obs, vec[t + 1][e]), (e, t)


def test_a_world_surrogate_of_its_own_moves_the_world_features_only() -> None:
    """A world surrogate whose means are shifted by a constant per feature (what a surrogate
    built at another fluid temperature would be, to first order): the features and the
    installation's reference move by that shift, the monitor keeps the nominal model."""
    import dataclasses

    sur = default_surrogate()
    shift = np.linspace(0.1, 0.7, len(sur.features))[:, None, None] * sur.run_std[:, :1, :1]
    hot = dataclasses.replace(sur, mean=sur.mean + shift)
    nominal = _setup()
    st = make_setup(None, None, None, None, None, {}, None, hot)
    assert st.world_surrogate is hot and st.world_features is hot and st.surrogate is sur
    for f in nominal.filters._fields:
        assert _same(getattr(st.filters, f), getattr(nominal.filters, f)), f
    assert _same(st.go_limits, nominal.go_limits)
    outs = []
    for world in (None, hot):
        env = gym.make(ENV_ID, world_surrogate=world)
        env.reset(seed=11)
        *_, info = env.step(0)
        a = env.unwrapped.batch.a
        outs.append(
            (np.array([info["features"][f] for f in FLIGHT_FEATURES]), a["reference"][0].copy())
        )
    idx = [sur.index(f) for f in FLIGHT_FEATURES]
    np.testing.assert_allclose(outs[1][0] - outs[0][0], shift[idx, 0, 0], rtol=1e-9, atol=1e-15)
    g = [sur.index("G1"), sur.index("G3")]
    np.testing.assert_allclose(outs[1][1] - outs[0][1], shift[g, 0, 0], rtol=1e-6, atol=1e-15)
    both = make_setup(None, None, None, None, None, {}, Mismatch(sensing_noise=2.0), hot)
    np.testing.assert_array_equal(both.world_features.run_std, 2.0 * hot.run_std)
    with pytest.raises(ValueError, match="world_surrogate must be None or a SurrogateModel"):
        make_setup(None, None, None, None, None, {}, None, dataclasses.replace(
            sur, features=sur.features[::-1]))  # fmt: skip
    with pytest.raises(ValueError, match="physics fidelity simulates its features"):
        make_setup(None, None, None, None, None, {"fidelity": "physics"}, None, hot)


def _case(tmp_path, **tables) -> str:
    path = tmp_path / "case.toml"
    save_sections(path, tables)
    return str(path)


def test_the_benchmark_runs_a_case_files_mismatch_table(tmp_path, capsys) -> None:
    """``scas-benchmark --scenario case.toml`` with a ``[mismatch]`` table runs that world: its
    episodes are those of ``run_benchmark`` with ``mismatch=`` (row for row), a spring growing
    5x faster fails within 400 slots where the nominal one does not, and the run records and
    prints the world."""
    import csv
    import json

    from policies.benchmark import run_benchmark
    from policies.cli import benchmark as benchmark_cli

    world = Mismatch(crack_growth=5.0)
    case = _case(tmp_path, scenario=Scenario(episode_slots=400), mismatch=world)
    out = tmp_path / "bench"
    argv = ["--scenario", case, "--episodes", "2", "--policies", "corrective", "--workers", "1"]
    assert benchmark_cli.main([*argv, "--out", str(out), "-q"]) == 0
    with (out / "results.csv").open() as f:
        rewards = [float(row["reward"]) for row in csv.DictReader(f)]
    runs = {
        m: run_benchmark(["corrective"], episodes=2, slots=400, env_kwargs=kw)
        for m, kw in (("world", {"mismatch": world}), ("nominal", {}))
    }
    assert rewards == [row["reward"] for row in runs["world"].rows]
    assert sum(row["failures_spring"] for row in runs["world"].rows) > 0
    assert sum(row["failures_spring"] for row in runs["nominal"].rows) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert Mismatch.from_dict(summary["config"]["mismatch"]) == world
    assert "(Mismatch): {'crack_growth': 5.0}" in (out / "summary.md").read_text()


def test_a_case_file_names_the_world_s_feature_surrogate(tmp_path, capsys) -> None:
    """``[mismatch] world_surrogate = "FILE"`` (relative to the case file) makes the world
    draw its features from that surrogate while the monitor keeps its own: the benchmark's
    episodes are those of ``run_benchmark`` with ``world_surrogate=`` row for row (the filter
    rule's rewards move with 5x run noise), alone or beside multipliers; the run records the
    file and its SHA-256; a missing file is a usage error naming the key."""
    import csv
    import dataclasses
    import hashlib
    import json

    from policies.benchmark import run_benchmark
    from policies.cli import benchmark as benchmark_cli

    nominal = default_surrogate()
    noisy = dataclasses.replace(nominal, run_std=nominal.run_std * 5.0)
    (tmp_path / "worlds").mkdir()
    noisy.save(tmp_path / "worlds" / "noisy.json")
    case = tmp_path / "case.toml"
    case.write_text('[scenario]\nepisode_slots = 1500\n[mismatch]\nworld_surrogate = '
                    '"worlds/noisy.json"\n')  # fmt: skip
    out = tmp_path / "bench"
    argv = ["--scenario", str(case), "--episodes", "2", "--policies", "rul_risk", "--workers",
            "1", "--out", str(out), "-q"]  # fmt: skip
    assert benchmark_cli.main(argv) == 0
    with (out / "results.csv").open() as f:
        rewards = [float(row["reward"]) for row in csv.DictReader(f)]
    runs = {
        name: run_benchmark(["rul_risk"], episodes=2, slots=1500, env_kwargs=kw)
        for name, kw in (("world", {"world_surrogate": noisy}), ("nominal", {}))
    }
    assert rewards == [row["reward"] for row in runs["world"].rows]
    assert rewards != [row["reward"] for row in runs["nominal"].rows]
    config = json.loads((out / "summary.json").read_text())["config"]
    digest = hashlib.sha256((tmp_path / "worlds" / "noisy.json").read_bytes()).hexdigest()
    assert config["world_surrogate"] == {
        "file": str(tmp_path / "worlds" / "noisy.json"),
        "sha256": digest,
    }
    case.write_text('[mismatch]\nworld_surrogate = "missing.json"\ncrack_growth = 2.0\n')
    with pytest.raises(SystemExit):
        benchmark_cli.main([*argv[:-3], "--out", str(tmp_path / "b2")])
    err = capsys.readouterr().err
    assert "[mismatch] world_surrogate = 'missing.json': cannot read" in err
    assert not (tmp_path / "b2").exists()


@pytest.mark.parametrize(
    ("command", "tables", "message"),
    [
        ("train", {"mismatch": Mismatch(crack_growth=2.0)}, "holds a [mismatch] table"),
        ("value", {"params": None}, "holds a [params] table"),
        ("benchmark", {"fleet": None, "mismatch": Mismatch()}, "a fleet runs the monitor"),
        ("benchmark", {"mismatch": {"crack_grow": 2.0}}, "unknown key(s) ['crack_grow']"),
    ],
)
def test_a_table_a_command_does_not_read_is_a_usage_error(
    command, tables, message, tmp_path, capsys
) -> None:
    """No command drops a case file's table silently: [params] (no command reads it),
    [mismatch] where the command runs the monitor's world (training; fleets), a bad
    [mismatch] key; usage errors before any work, nothing written."""
    import importlib

    from scas_env.actuator.params import ScasParams
    from scas_env.core.fleet.config import FleetConfig

    objects = {"params": ScasParams(), "fleet": FleetConfig()}
    path = tmp_path / "case.toml"
    data = {k: objects[k] if v is None else v for k, v in tables.items()}
    if isinstance(data.get("mismatch"), dict):  # a raw table with a misspelt key
        path.write_text("[scenario]\nepisode_slots = 50\n[mismatch]\ncrack_grow = 2.0\n")
    else:
        save_sections(path, {"scenario": Scenario(episode_slots=50), **data})
    out = tmp_path / "out"
    main = importlib.import_module(f"policies.cli.{command}").main
    with pytest.raises(SystemExit) as exit_:
        main(["--scenario", str(path), "--out", str(out)])
    assert exit_.value.code == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_a_case_file_of_a_mismatch_alone_runs_the_default_scenario(tmp_path, capsys) -> None:
    """A file holding only ``[mismatch]`` reads as the default scenario in that world (as a
    fleet alone does); its bad value is the error, not a missing [scenario] table."""
    from policies.cli import benchmark as benchmark_cli
    from scas_env.cli_args import load_env_config, load_world

    path = tmp_path / "world.toml"
    path.write_text("[mismatch]\ncrack_growth = 2.0\n")
    parser = benchmark_cli.build_parser()
    args = parser.parse_args(["--scenario", str(path)])
    scenario, _ = load_env_config(parser, args, fleet=True, mismatch=True)
    assert scenario == Scenario() and load_world(parser, args).mismatch == Mismatch(
        crack_growth=2.0
    )
    path.write_text("[mismatch]\ncrack_growth = 0\n")
    with pytest.raises(SystemExit):
        benchmark_cli.main(["--scenario", str(path), "--out", str(tmp_path / "o")])
    assert "Mismatch.crack_growth = 0" in capsys.readouterr().err
