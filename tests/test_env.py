"""ScasMaintenance-v2, the single env (a batch of one): API conformance, registration,
determinism and copies, bad inputs, the reward's accounting and the episode's mechanics."""

from __future__ import annotations

import copy
import enum
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
import scipy.stats
from gymnasium.error import DeprecatedEnv
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import scas_env
from scas_env.core.costs import CostModel
from scas_env.core.scenario import OBS_MODES, Scenario
from scas_env.core.setup import PARTS
from scas_env.env import ScasMaintenanceEnv

ENV_ID = scas_env.ENV_ID
#: the observation of the default mode, in order (the env's docstring table)
OBS_NAMES = (
    "I2", "I6", "I7", "I8", "I9", "G1", "G3", "test_age", "no_go",
    "spring_rul_mean", "spring_rul_low", "spring_risk", "seal_rul_mean", "seal_rul_low",
    "seal_risk", "spring_alarm", "seal_alarm", "spring_age", "seal_age", "downtime",
)  # fmt: skip
OBS_UNITS = (
    "-", "mm", "uA/mm", "uA", "-", "uA", "uA/mm", "slots", "0/1", "flights", "flights", "-",
    "flights", "flights", "-", "0/1", "0/1", "flights", "flights", "slots",
)  # fmt: skip


def _flat(obs) -> np.ndarray:
    if isinstance(obs, dict):
        return np.concatenate([obs[k] for k in sorted(obs)])
    return obs


def _actions(n: int, seed: int = 0) -> list[int]:
    rng = np.random.default_rng(seed)
    return rng.choice(4, size=n, p=[0.8, 0.15, 0.025, 0.025]).tolist()


def _rollout(env: gym.Env, actions: list[int], seed: int | None) -> list[tuple]:
    """Everything the env returns, step by step (``seed=None``: continue the episode)."""
    out = []
    if seed is not None:
        obs, info = env.reset(seed=seed)
        out.append((_flat(obs).tobytes(), copy.deepcopy(info)))
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append((_flat(obs).tobytes(), r, term, trunc, copy.deepcopy(info)))
    return out


# ----------------------------------------------------------------------------- conformance
@pytest.mark.parametrize("obs_mode", OBS_MODES)
def test_gymnasium_and_sb3_checkers_pass_without_warnings(obs_mode: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        gym_check_env(ScasMaintenanceEnv(obs_mode=obs_mode, episode_slots=50),
                      skip_render_check=True)  # fmt: skip
        sb3_check_env(ScasMaintenanceEnv(obs_mode=obs_mode, episode_slots=50), warn=True)


def test_one_registered_version_and_the_retired_ids() -> None:
    """v2 is the only version: ``ENV_ID`` with its vector entry point; v0, v1, Epochs-v0 and
    the decision-epoch env's old name Epochs-v1 are retired (Gymnasium's ``DeprecatedEnv``
    naming the current id); the old module-level names are gone."""
    assert ENV_ID == "scas_env/ScasMaintenance-v2"
    assert scas_env.ENV_ID_EPOCHS == "scas_env/ScasMaintenanceEpochs-v2"
    spec = gym.spec(ENV_ID)
    assert spec.entry_point == "scas_env.env:ScasMaintenanceEnv"
    assert spec.vector_entry_point == "scas_env.vector_env:make_vector_env"
    assert spec.kwargs == {} and spec.max_episode_steps is None
    env = gym.make(ENV_ID, episode_slots=5)
    assert env.unwrapped.scenario == Scenario(episode_slots=5)
    for old, new in (
        ("scas_env/ScasMaintenance-v0", ENV_ID),
        ("scas_env/ScasMaintenance-v1", ENV_ID),
        ("scas_env/ScasMaintenanceEpochs-v0", scas_env.ENV_ID_EPOCHS),
        ("scas_env/ScasMaintenanceEpochs-v1", scas_env.ENV_ID_EPOCHS),
    ):
        assert old not in gym.registry
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            with pytest.raises(DeprecatedEnv, match=f"Please use `{new}`"):
                gym.make(old)
    new_obs, _ = gym.make(scas_env.ENV_ID_EPOCHS, episode_slots=30).reset(seed=0)
    assert new_obs.shape == (21,)  # the per-flight env's 20 entries and flights_left
    for gone in ("V2_KWARGS", "ENV_ID_V2", "ENV_ID_V1", "ENV_ID_EPOCHS_V2"):
        assert not hasattr(scas_env, gone), gone
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing a user runs warns about the version asked for
        gym.make(ENV_ID).reset(seed=0)
        gym.make(scas_env.ENV_ID_EPOCHS).reset(seed=0)


def test_default_scenario_is_the_current_version() -> None:
    s = Scenario()
    assert (s.fidelity, s.obs_mode, s.initial_health, s.preflight) == (
        "surrogate", "features+rul", "new", "on_demand")  # fmt: skip
    assert (s.episode_slots, s.flight_update_flights, s.reference_tests) == (2000, 10, 4)
    for removed in ("go_no_go", "flight_features", "degradation_draws", "damage_scatter",
                    "go_no_go_false_alarm", "spring_effect_realign", "kernel_threads"):  # fmt: skip
        assert not hasattr(s, removed)
        with pytest.raises(ValueError, match=removed):
            ScasMaintenanceEnv(**{removed: 1})


def test_observation_names_units_and_bounds() -> None:
    env = ScasMaintenanceEnv()
    assert env.obs_names == OBS_NAMES and env.obs_units == OBS_UNITS
    assert env.observation_space.shape == (20,) and env.observation_space.dtype == np.float32
    assert np.all(np.isfinite(env.observation_space.low))
    assert np.all(np.isfinite(env.observation_space.high))
    obs, _ = env.reset(seed=3)
    assert env.observation_space.contains(obs)
    for a in _actions(300, 3):
        obs, *_, info = env.step(a)
        assert env.observation_space.contains(obs) and obs.dtype == np.float32
        b = env.batch.a
        assert obs[OBS_NAMES.index("test_age")] == b["test_age"][0]
        assert obs[OBS_NAMES.index("downtime")] == info["downtime"] == env.downtime
        assert obs[OBS_NAMES.index("spring_age")] == env.part_age["spring"]
        assert obs[OBS_NAMES.index("seal_age")] == b["part_age"][0, 1]
        assert obs[OBS_NAMES.index("no_go")] == b["no_go"][0]
        for f, factor in (("I2", 1.0), ("I6", 1e3), ("I7", 1e3), ("I8", 1e6), ("I9", 1.0),
                          ("G1", 1e6), ("G3", 1e3)):  # fmt: skip
            lo, hi = (env.observation_space.low[OBS_NAMES.index(f)],
                      env.observation_space.high[OBS_NAMES.index(f)])  # fmt: skip
            assert obs[OBS_NAMES.index(f)] == np.float32(
                np.clip(info["features"][f] * factor, lo, hi)
            )


def test_other_observation_modes() -> None:
    env = ScasMaintenanceEnv(obs_mode="features")
    assert env.obs_names == OBS_NAMES[:9] + OBS_NAMES[15:]
    env = ScasMaintenanceEnv(obs_mode="state")
    assert env.obs_names[:7] == (
        "crack_fraction", "wear_fraction", "spring_rul_true", "seal_rul_true", "spring_age",
        "seal_age", "downtime")  # fmt: skip
    obs, info = env.reset(seed=0)
    assert obs[0] == np.float32(info["true_state"]["crack_fraction"])
    assert obs[2] == np.float32(info["true_state"]["spring_rul_flights"])
    env = ScasMaintenanceEnv(obs_mode="dict")
    obs, _ = env.reset(seed=0)
    assert set(obs) == {"features", "filter", "monitor", "state"}
    assert env.observation_space.contains(obs)


# ----------------------------------------------------------------------------- determinism
@pytest.mark.parametrize(("fidelity", "n"), [("surrogate", 300), ("physics", 6)])
def test_same_seed_same_actions_same_episode_bit_for_bit(fidelity: str, n: int) -> None:
    actions = _actions(n, 1) if fidelity == "surrogate" else [1, 0, 2, 1, 3, 1]
    kw = {"fidelity": fidelity, **({"window_library": 2} if fidelity == "physics" else {})}
    a = _rollout(ScasMaintenanceEnv(**kw), actions, seed=7)
    b = _rollout(ScasMaintenanceEnv(**kw), actions, seed=7)
    c = _rollout(ScasMaintenanceEnv(**kw), actions, seed=8)
    assert a == b
    assert any(x[0] != y[0] for x, y in zip(a, c, strict=True))


def test_reset_without_seed_continues_the_generator_and_a_reseed_repeats() -> None:
    env = ScasMaintenanceEnv(episode_slots=40)
    first = _rollout(env, [0] * 40, seed=5)
    env.reset()  # a new episode from the same np_random: a new unit
    second = _rollout(env, [0] * 40, seed=None)
    again = _rollout(ScasMaintenanceEnv(episode_slots=40), [0] * 40, seed=5)
    assert first == again and first[1:] != second


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
@pytest.mark.parametrize("fidelity", ["surrogate", "physics"])
def test_copies_continue_identically(how: str, fidelity: str) -> None:
    """A copy mid-episode (after tests, replacements and a learning update) continues the
    episode bit for bit, its streams its own: stepping the copy leaves the original alone."""
    n_before, n_after = (60, 300) if fidelity == "surrogate" else (3, 4)
    env = ScasMaintenanceEnv(fidelity=fidelity, window_library=2 if fidelity == "physics" else 64)
    env.reset(seed=11)
    for a in ([2, 1, 0, *_actions(n_before, 2)])[:n_before]:
        env.step(a)
    clone = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    actions = _actions(n_after, 4)
    assert _rollout(clone, actions, None) == _rollout(env, actions, None)
    assert clone.batch.a is not env.batch.a
    assert clone.batch.rngs[0]["measure"] is not env.batch.rngs[0]["measure"]


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_copies_hand_the_kernels_the_types_they_were_compiled_for(how: str) -> None:
    """Every argument group of the kernels has the same numba type in a copy (pickle gives
    arrays back writeable: a read-only table would then be another type, and every kernel
    would compile a second time, about a minute, on the copy's first step)."""
    import numba

    env = ScasMaintenanceEnv()
    env.reset(seed=1)
    clone = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    setup_fields = ("world", "filters", "detector", "go_limits", "learn_cols")
    for name in setup_fields:
        assert numba.typeof(getattr(clone.setup, name)) == numba.typeof(getattr(env.setup, name)), (
            name
        )
    batch_groups = ("_world", "_monitor", "_memory", "_books", "_handles", "_out", "tables",
                    "bank", "_prices")  # fmt: skip
    for name in batch_groups:
        assert numba.typeof(getattr(clone.batch, name)) == numba.typeof(getattr(env.batch, name)), (
            name
        )


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    "action",
    [4, -1, 2.5, 1.0, "3", "fly", None, True, False, np.bool_(True), np.timedelta64(2),
     np.int64(4), np.int64(-1), np.array([1]), np.array(True), np.float64(1), [1]],
    ids=repr,
)  # fmt: skip
def test_bad_actions_raise(action) -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(action)
    assert env.slot == 0  # nothing happened


class _Action(enum.IntEnum):
    FLY, TEST = 0, 1


@pytest.mark.parametrize(
    "action",
    [1, np.int64(1), np.int32(1), np.uint8(1), np.uint64(1), np.array(1), _Action.TEST],
    ids=repr,
)
def test_integer_actions_of_any_kind_are_accepted(action) -> None:
    """Also an ``IntEnum`` member, which ``Discrete(4).contains`` accepts."""
    env = ScasMaintenanceEnv()
    env.reset(seed=0)
    *_, info = env.step(action)
    assert info["tests"] == 1


def test_step_before_reset_and_bad_seeds_raise() -> None:
    env = ScasMaintenanceEnv()
    with pytest.raises(RuntimeError, match="reset"):
        env.step(0)
    with pytest.raises(RuntimeError, match="reset"):
        env.part_lives()
    for seed in (-1, 1.5, "0", True):
        with pytest.raises(ValueError, match="seed"):
            env.reset(seed=seed)


def test_numpy_integer_seeds_give_the_python_seeds_episode() -> None:
    a, b = ScasMaintenanceEnv(), ScasMaintenanceEnv()
    np.testing.assert_array_equal(a.reset(seed=np.uint32(7))[0], b.reset(seed=7)[0])
    np.testing.assert_array_equal(a.step(1)[0], b.step(1)[0])


@pytest.mark.parametrize("options", [[], 0, "", {"x": 1}, ("a",)])
def test_options_other_than_none_or_empty_raise(options) -> None:
    env = ScasMaintenanceEnv()
    with pytest.raises(ValueError, match="options"):
        env.reset(seed=0, options=options)
    env.reset(seed=0, options={})  # an empty dict is no option


def test_stepping_past_truncation_raises_until_reset() -> None:
    env = ScasMaintenanceEnv(episode_slots=2)
    env.reset(seed=0)
    assert [env.step(0)[3] for _ in range(2)] == [False, True]
    with pytest.raises(RuntimeError, match="truncated at slot 2"):
        env.step(0)
    env.reset()
    assert env.step(0)[3] is False


def test_bad_configs_raise_clear_errors() -> None:
    from scas_env.actuator.params import ActuatorParams

    with pytest.raises(ValueError, match=r"seal_friction_n = 0.0 N is outside .* \(0, "):
        ActuatorParams(seal_friction_n=0.0)  # no friction, no Archard wear: refused up front
    for name in ("calibration", "surrogate", "params", "cost_model", "scenario"):
        with pytest.raises(ValueError, match=name):
            ScasMaintenanceEnv(**{name: "x"})
    with pytest.raises(ValueError, match="unknown key"):
        gym.make(ENV_ID, episode_slot=10)
    with pytest.raises(ValueError, match="obs_mode"):
        ScasMaintenanceEnv(obs_mode="pixels")
    with pytest.raises(ValueError, match="episode_slots"):
        ScasMaintenanceEnv(episode_slots=0)
    with pytest.raises(ValueError, match="not both"):
        ScasMaintenanceEnv(scenario=Scenario(), episode_slots=3)
    with pytest.raises(ValueError, match="window_library"):
        ScasMaintenanceEnv(fidelity="physics", window_library=-1)
    with pytest.raises(ValueError, match="at least one of crack_active, wear_active"):
        ScasMaintenanceEnv(crack_active=0, wear_active=0)
    for mode in (1, "rgb", ["ansi"]):
        with pytest.raises(ValueError, match=r"render_mode = .* must be None or one of"):
            ScasMaintenanceEnv(render_mode=mode)


def test_ansi_render_shows_the_state() -> None:
    env = ScasMaintenanceEnv(render_mode="ansi")
    env.reset(seed=0)
    env.step(0)
    text = env.render()
    assert text.startswith("slot 1: crack ") and "availability 1.000" in text
    assert ScasMaintenanceEnv().render() is None


# ----------------------------------------------------------------------------- mechanics
def test_action_masks_read_the_ground_and_the_parts_ages() -> None:
    """The single env's ``action_masks()`` (MaskablePPO's protocol) over a random episode with
    failures, replacements and downtime: test only off the ground, replace only a part that
    has flown, read from the observation's downtime and ages independently; the decision-epoch
    wrapper's mask is it, repeated per k; before reset it is refused."""
    from scas_env.decision_epochs import DecisionEpochs

    env = ScasMaintenanceEnv(episode_slots=400, cost_model=CostModel(seal_downtime_slots=3))
    with pytest.raises(RuntimeError, match="reset"):
        env.action_masks()
    names = env.obs_names
    col = {k: names.index(k) for k in ("downtime", "spring_age", "seal_age")}
    obs, _ = env.reset(seed=5)
    rng = np.random.default_rng(5)
    seen = {"ground": 0, "new part": 0}
    for _ in range(400):
        mask = env.action_masks()
        down, spring, seal = (obs[col[k]] for k in col)
        assert mask.tolist() == [True, down == 0, spring > 0, seal > 0]
        seen["ground"] += down > 0
        seen["new part"] += spring == 0 or seal == 0
        obs, *_ = env.step(int(rng.choice(4, p=[0.9, 0.05, 0.02, 0.03])))
    assert seen["ground"] > 0 and seen["new part"] > 1
    epochs = DecisionEpochs(ScasMaintenanceEnv(episode_slots=400), ks=(1, 5))
    epochs.reset(seed=0)
    for action in (6, 0, 1):  # replace the seals (on the ground), then fly
        inner = epochs.env.unwrapped.action_masks()
        np.testing.assert_array_equal(epochs.action_masks(), np.repeat(inner, 2))
        epochs.step(action)


def test_reward_accounting_matches_cost_model() -> None:
    costs = CostModel(test_usd=123.0, flight_value_usd=1000.0, spring_downtime_slots=2)
    env = ScasMaintenanceEnv(cost_model=costs)
    env.reset(seed=0)
    _, r, *_, info = env.step(1)
    assert info["reward_terms"] == {"flight": 1000.0, "test": -123.0, "no_go": 0.0,
                                    "replacement": 0.0, "failure": 0.0}  # fmt: skip
    assert r == 1000.0 - 123.0
    _, r, *_, info = env.step(2)  # spring change: the slot on the ground, parts cost
    assert r == -costs.spring_replacement_usd and info["replacements"]["spring"] == 1
    assert info["downtime"] == 2 and info["flights"] == 1
    for expected in (1, 0):  # the extra downtime: nothing flies, nothing is paid
        _, r, *_, info = env.step(1)
        assert r == 0.0 and info["downtime"] == expected and info["tests"] == 1
    _, r, *_, info = env.step(0)
    assert r == 1000.0 and info["flights"] == 2
    assert info["cost_usd"] == 123.0 + costs.spring_replacement_usd
    assert info["revenue_usd"] == 2000.0 and info["availability"] == 2 / 5


def test_running_totals_are_the_sums_of_the_steps() -> None:
    env = ScasMaintenanceEnv(initial_health="random", episode_slots=600)
    env.reset(seed=4)
    total = {"reward": 0.0, "cost": 0.0, "revenue": 0.0}
    for a in _actions(600, 8):
        _, r, _, trunc, info = env.step(a)
        terms = info["reward_terms"]
        assert r == sum(terms.values())
        total["reward"] += r
        total["revenue"] += terms["flight"]
        total["cost"] -= r - terms["flight"]
    assert trunc and info["slot"] == 600
    assert info["revenue_usd"] == pytest.approx(total["revenue"], rel=1e-12)
    assert info["cost_usd"] == pytest.approx(total["cost"], rel=1e-12)
    assert info["revenue_usd"] - info["cost_usd"] == pytest.approx(total["reward"], rel=1e-12)
    assert info["availability"] == info["flights"] / 600


def _nested_keys(d: dict, prefix: str = "") -> set[str]:
    out = set()
    for k, v in d.items():
        out.add(prefix + k)
        if isinstance(v, dict):
            out |= _nested_keys(v, prefix + k + ".")
    return out


def test_wasted_life_is_the_true_rul_thrown_away_and_info_keeps_its_size() -> None:
    env = ScasMaintenanceEnv()
    _, info = env.reset(seed=2)
    keys = _nested_keys(info)
    thrown = {"spring": [], "seal": []}
    rng = np.random.default_rng(0)
    for _ in range(400):
        action = int(rng.choice(4, p=[0.6, 0.2, 0.1, 0.1]))
        before = info["true_state"]
        _, _, _, _, info = env.step(action)
        assert _nested_keys(info) == keys
        for k, part in ((2, "spring"), (3, "seal")):
            now = info["wasted_life_flights"][part]
            if action == k:
                rul = before[f"{part}_rul_flights"]
                assert now == min(rul, env.scenario.rul_cap_flights)
                thrown[part].append(now)
            else:
                assert now == 0.0
    for part, values in thrown.items():
        assert len(values) > 5
        assert info["wasted_life_count"][part] == len(values)
        assert info["wasted_life_sum_flights"][part] == pytest.approx(sum(values), rel=1e-12)


def _run_to_failure_timeline(
    lives: dict[str, list[float]], slots: int, downtime_slots: int
) -> tuple[dict[str, int], int]:
    """Failures per part and flights flown when only ``fly`` is chosen, from the announced
    lives alone: every flight attempt ages both parts, a part fails on the attempt that
    ends its life (not flown; the next announced part is fitted) and the aircraft is then
    down for ``downtime_slots`` slots."""
    left = {p: list(v) for p, v in lives.items()}
    failures, flights, down = dict.fromkeys(lives, 0), 0, 0
    for _ in range(slots):
        if down > 0:
            down -= 1
            continue
        for p in left:
            left[p][0] -= 1.0
        failed = [p for p in left if left[p][0] <= 0.0]
        for p in failed:
            failures[p] += 1
            left[p].pop(0)
        if failed:
            down = downtime_slots
        else:
            flights += 1
    return failures, flights


def test_never_maintained_unit_fails_and_failed_part_is_renewed() -> None:
    """Run to failure: the failures per part and the flights flown are those the announced
    lives imply (``part_lives``, an independent timeline); at each failure the failed part
    (the one whose count went up) is renewed: age 0, the next announced life, a new seal
    with no wear; the other part is kept (its age and remaining life go on)."""
    slots = 3000
    env = ScasMaintenanceEnv(episode_slots=slots)
    env.reset(seed=5)
    lives = env.part_lives(count=8)
    expected, flights = _run_to_failure_timeline(
        lives, slots, int(env.costs.failure_downtime_slots)
    )
    fitted = dict.fromkeys(PARTS, 0)  # index of the fitted part in the announced lives
    before = {p: 0 for p in PARTS}
    failures = 0
    for _ in range(slots):
        _, r, _, _, info = env.step(0)
        failed = [p for p in PARTS if info["failures"][p] > before[p]]
        if failed:
            failures += 1
            state, age = info["true_state"], env.batch.a["part_age"][0]
            for k, part in enumerate(PARTS):
                if part in failed:
                    fitted[part] += 1
                    assert age[k] == 0
                    assert state[f"{part}_rul_flights"] == lives[part][fitted[part]]
                else:
                    assert age[k] > 0
            if "seal" in failed:
                assert state["seal_wear_m"] == 0.0 == state["wear_fraction"]
            assert r == -env.costs.failure_total_usd
            assert info["downtime"] == env.costs.failure_downtime_slots
        before = dict(info["failures"])
    assert info["failures"] == expected
    assert expected["spring"] >= 1 and expected["seal"] >= 1  # both parts exercised
    assert sum(info["failures"].values()) == failures
    assert info["flights"] == flights
    assert info["replacements"] == info["failures"]  # failed parts only: none preventive
    assert info["availability"] < 1.0


def test_replacement_renews_the_part_and_its_filter() -> None:
    env = ScasMaintenanceEnv()
    env.reset(seed=9)
    a, cal = env.batch.a, env.calibration
    for _ in range(600):
        env.step(1)
    assert a["wear"][0] > 0.3 * cal.seal_critical_wear_m
    assert a["x"][0, 1] @ a["w"][0, 1] > 0.2 * cal.seal_critical_wear_m
    env.step(3)
    assert a["wear"][0] == 0.0 and env.part_age["seal"] == 0
    assert np.all(a["x"][0, 1] == 0.0)
    crack_before = a["crack"][0]
    env.step(2)
    assert a["crack"][0] < crack_before and env.part_age["spring"] == 0
    # the new spring's filter restarts from its prior: N(a0, sd) truncated to [0, failure
    # depth], equal weights; its mean within 4 standard errors of the prior's (scipy)
    x, w = a["x"][0, 0], a["w"][0, 0]
    np.testing.assert_array_equal(w, 1.0 / x.size)
    a0, sd = env.params.spring.initial_crack_m, env.params.uncertainty.initial_crack_sigma_m
    prior = scipy.stats.truncnorm(-a0 / sd, (cal.spring_failure_depth_m - a0) / sd, a0, sd)
    assert x @ w == pytest.approx(prior.mean(), abs=4 * prior.std() / np.sqrt(x.size))


def test_filter_tracks_seal_wear_under_regular_tests() -> None:
    """Testing every 5 flights, after the first 300 flights of a seal set: the seal
    filter's mean follows the true wear (units 0-3; median error a few % of critical:
    1-3 % measured, under 4 % at every unit required)."""
    medians = []
    for seed in range(4):
        env = ScasMaintenanceEnv()
        env.reset(seed=seed)
        a, crit = env.batch.a, env.calibration.seal_critical_wear_m
        truth, est = [], []
        for k in range(900):
            env.step(1 if k % 5 == 0 else 0)
            if env.part_age["seal"] > 300 and a["wear"][0] < 0.95 * crit:
                truth.append(float(a["wear"][0]))
                est.append(float(a["x"][0, 1] @ a["w"][0, 1]))
        truth, est = np.array(truth), np.array(est)
        assert truth.size > 100
        assert np.corrcoef(truth, est)[0, 1] > 0.97
        medians.append(np.median(np.abs(est - truth)) / crit)
    assert max(medians) < 0.04, medians


def test_failed_go_no_go_grounds_the_slot_and_shows_in_the_observation() -> None:
    k = OBS_NAMES.index("no_go")
    for seed in range(20):  # a part at 97 % of critical fails the test with p ~ 0.85
        env = ScasMaintenanceEnv()
        env.reset(seed=seed)
        env.batch.a["wear"][0] = 0.97 * env.calibration.seal_critical_wear_m
        obs, r, _, _, info = env.step(1)
        if info["no_go"] == 1:
            break
    assert obs[k] == 1.0 and info["flights"] == 0
    assert r == -(env.costs.test_usd + env.costs.no_go_inspection_usd)
    obs, r, *_, info = env.step(0)  # held: no untested flight after a no-go
    assert obs[k] == 1.0 and r == 0.0 and info["flights"] == 0
    obs, *_ = env.step(3)  # new seals: the failed test has been answered
    assert obs[k] == 0.0
    env.step(0)  # the reseal's extra downtime slot
    obs, r, *_ = env.step(1)
    assert obs[k] == 0.0
    assert r == env.costs.flight_value_usd - env.costs.test_usd


@pytest.mark.slow
def test_long_surrogate_run_stays_finite_with_bounded_memory() -> None:
    import tracemalloc

    env = ScasMaintenanceEnv(episode_slots=100_000)
    env.reset(seed=1)
    actions = _actions(100_000, 9)
    tracemalloc.start()
    for k, a in enumerate(actions):
        obs, r, _, trunc, _ = env.step(a)
        assert np.all(np.isfinite(obs)) and np.isfinite(r)
        if k == 10_000:
            base = tracemalloc.get_traced_memory()[0]
    grown = tracemalloc.get_traced_memory()[0] - base
    tracemalloc.stop()
    assert trunc
    assert grown < 20e6


def test_physics_window_library_reuses_windows_and_their_baselines() -> None:
    from scas_env.actuator.sensing import draw_window

    env = ScasMaintenanceEnv(fidelity="physics", window_library=2)
    env.reset(seed=4)
    for _ in range(5):
        env.step(0)
    row = env.batch.physics[0]
    assert 1 <= len(row.windows) <= 2  # five flights, at most two distinct windows
    k, window = next(iter(row.windows.items()))
    again = draw_window(
        env.params,
        np.random.default_rng((row.library_seed, k)),
        env.params.mission.flight_window_s,
    )
    np.testing.assert_array_equal(window.profile.scas_command_m, again.profile.scas_command_m)
    np.testing.assert_array_equal(window.baseline.current_a, again.baseline.current_a)


def test_physics_episode_flies_tests_and_renews_parts() -> None:
    """The physics fidelity runs the current version: measured features feed the same
    filters and books (tests, a no-go-free flight, replacements)."""
    env = ScasMaintenanceEnv(fidelity="physics", window_library=2)
    obs, _ = env.reset(seed=1)
    for action in (1, 0, 3, 0, 0, 2):
        obs, r, _, _, info = env.step(action)
        assert env.observation_space.contains(obs) and np.isfinite(r)
    assert info["tests"] == 1 and info["replacements"] == {"spring": 1, "seal": 1}
    assert info["flights"] >= 3 and np.all(np.isfinite(list(info["features"].values())))


def test_a_failed_filter_update_ends_the_episode_until_reset() -> None:
    """A particle pushed out of range makes the next learning update fail. That step had
    grown the world without booking the slot; the env then went on from that state (and a
    vector env dropped the other rows' replacements). Now the next step asks for reset()."""
    from scas_env.vector_env import ScasMaintenanceVectorEnv

    env = ScasMaintenanceEnv(n_particles=100)
    venv = ScasMaintenanceVectorEnv(2, n_particles=100)
    for face, step in ((env, lambda: env.step(0)), (venv, lambda: venv.step(np.array([0, 3])))):
        face.reset(seed=1)
        for _ in range(5):
            step()
        face.batch.a["x"][0, 0, 3] = 1e200
        with pytest.raises(FloatingPointError, match=r"call reset\(\)"):
            for _ in range(20):  # the next learning update (a batch of 10 flights)
                step()
        with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
            step()
        face.reset(seed=1)
        step()
