"""Speed of the envs, each figure beside a reference measured in the same run (``make bench``).

    python -m experiments.env_speed                 # every figure, ~20 s
    python -m experiments.env_speed --json out.json

* **single env** (``ScasMaintenance-v2``, ``gym.make``): microseconds per step, flying only and
  with a pre-flight test every 10 slots, beside Gymnasium's ``CartPole-v1`` step;
* **native vector env** at 64 actuators: env-steps (actuator-slots) per second under the
  trained policy's mix (90 % fly, 9 % test, 1 % replace: the shipped agent's actions on
  v2) and flying only, beside CartPole's own native vector env at 64;
* **the filter arithmetic's ceiling** under that mix: the env-steps per second the vector env
  would reach if only the particle-filter updates cost time. The updates are counted in an
  untimed replay of the same actions (:func:`count_updates`: test updates; learning
  updates, a full batch of ``flight_update_flights`` flights or the part batch a test or a
  fitting learns first; RUL-table rebuilds, one per row whose clouds changed) and each kind
  is timed alone on the same batch (jitted loops of the kernels, every call from its state
  after 100 flying slots); ceiling = env-steps /
  (tests x t_test + learns x t_learn + rebuilds x t_rebuild); and what a step costs besides
  them when flying alone (the flight's degradation and feature draws, the observation, the
  info: the flying step's time less its updates and its failed parts' fitting), so the share
  of the ceiling a mix that also flies can reach at most: t_filters / (t_filters + t_flight);
  and fitting a part inside the mix (CPU time per fitting, per env-step);
* **the fleet** (``ScasFleet-v0``, 8 aircraft x 3 actuators, the naive rule at its defaults):
  actuator-flights per second and seconds per 365-day episode, beside the vector env's
  actuator-steps per second (the issue's target: the fleet flies at least half as many
  actuator-flights per second as the vector env steps actuators).

``--scenario JSON`` compares instead: the single env's and the native vector env's figures
with those Scenario fields beside the defaults, measured alternately in the same run, and
the slowdown of each (the option's time over the default's), e.g. the spring filter's
rejuvenation::

    python -m experiments.env_speed --scenario '{"rejuvenation": "resample_move"}'

Times are CPU seconds of this process (``time.process_time``), the best of a few repeats:
less sensitive than wall time to other jobs on a shared machine, not immune to them.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numba import njit

import scas_env
from scas_env.core import parts
from scas_env.core.filters import learn_row, refresh_row, test_row, work_arrays
from scas_env.utils.atomic_file import write_text_atomic
from scas_env.utils.results_folder import json_text

#: the trained policy's mix of actions (fly, test, replace spring, replace seal)
MIX = (0.90, 0.09, 0.005, 0.005)


def _best(fn: Callable[[], float], repeats: int = 3) -> float:
    return min(fn() for _ in range(repeats))


def _cpu(fn: Callable[[], Any]) -> float:
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


def single_env_us(steps: int = 6000, **fields: Any) -> dict[str, float]:
    """Microseconds per step of the single env (flying; a test every 10 slots) and of
    CartPole-v1, through ``gym.make`` (its wrappers included); ``fields``: Scenario fields
    over the defaults."""
    env = gym.make(scas_env.ENV_ID, **fields)
    cart = gym.make("CartPole-v1")

    def run(actions: Sequence[int]) -> float:
        env.reset(seed=0)

        def go() -> None:
            for a in actions:
                if env.step(a)[3]:
                    env.reset()

        return _cpu(go) / len(actions) * 1e6

    def cartpole() -> float:
        cart.reset(seed=0)

        def go() -> None:
            for _ in range(steps):
                if any(cart.step(0)[2:4]):
                    cart.reset()

        return _cpu(go) / steps * 1e6

    fly = [0] * steps
    tested = [1 if k % 10 == 0 else 0 for k in range(steps)]
    run(tested[:500])  # compile and warm
    return {
        "cartpole_us": _best(cartpole),
        "fly_us": _best(lambda: run(fly)),
        "test_every_10_us": _best(lambda: run(tested)),
    }


def vector_rates(num_envs: int = 64, steps: int = 600, **fields: Any) -> dict[str, float]:
    """Env-steps per second of the native vector env under :data:`MIX` and flying only,
    CartPole's native vector env, and the filter updates of the mix (counts and the
    ceiling, module docstring); ``fields``: Scenario fields over the defaults."""
    rng = np.random.default_rng(0)
    mix = rng.choice(4, size=(100 + steps * 3, num_envs), p=MIX)
    fly = np.zeros_like(mix)

    def make() -> Any:
        return gym.make_vec(scas_env.ENV_ID, num_envs=num_envs,
                            vectorization_mode="vector_entry_point", **fields)  # fmt: skip

    def rate(actions: np.ndarray) -> float:
        """The best of three runs of ``actions[100:]`` in thirds after ``actions[:100]``."""
        venv = make()
        venv.reset(seed=0)
        for a in actions[:100]:
            venv.step(a)

        def go(part: np.ndarray) -> float:
            return num_envs * len(part) / _cpu(lambda: [venv.step(a) for a in part])

        return max(go(part) for part in np.array_split(actions[100:], 3))

    mix_rate, fly_rate = rate(mix), rate(fly)
    n_mix, n_fly = count_updates(make(), mix), count_updates(make(), fly)
    cart = gym.make_vec("CartPole-v1", num_envs=num_envs, vectorization_mode="vector_entry_point")
    cart.reset(seed=0)
    zeros = np.zeros(num_envs, dtype=np.int64)

    def cart_rate() -> float:
        return num_envs * steps / _cpu(lambda: [cart.step(zeros) for _ in range(steps)])

    costs = update_costs(make())

    def filter_time(n: dict[str, float]) -> float:
        return sum(n[k] * costs[k] for k in costs)

    def fitting_time(n: dict[str, float]) -> float:  # less its learning updates (counted)
        return n["fitting_s"] - n["fitting_learn"] * costs["learn"]

    ceiling = 1.0 / filter_time(n_mix)
    # the flight, observation and info: flying less its updates and its failed parts' fitting
    fly_other = 1.0 / fly_rate - filter_time(n_fly) - fitting_time(n_fly)
    return {
        "mix_steps_per_s": mix_rate,
        "fly_steps_per_s": fly_rate,
        "cartpole_vector_steps_per_s": max(cart_rate() for _ in range(3)),
        "tests_per_step": n_mix["test"],
        "learns_per_step": n_mix["learn"],
        "rebuilds_per_step": n_mix["rebuild"],
        "test_update_us": costs["test"] * 1e6,
        "learn_update_us": costs["learn"] * 1e6,
        "rebuild_us": costs["rebuild"] * 1e6,
        "filter_ceiling_steps_per_s": ceiling,
        "share_of_ceiling": mix_rate / ceiling,
        "fly_other_us": fly_other * 1e6,
        "share_cap_with_flight": (1.0 / ceiling) / (1.0 / ceiling + fly_other),
        "fitting_us": n_mix["fitting_s"] / n_mix["fitting"] * 1e6 if n_mix["fitting"] else math.nan,
        "fitting_us_per_step": n_mix["fitting_s"] * 1e6,
        "fitting_net_us_per_step": fitting_time(n_mix) * 1e6,
    }


def count_updates(venv: Any, actions: np.ndarray) -> dict[str, float]:
    """Filter updates per env-step of ``actions[100:]`` after ``actions[:100]`` in ``venv``
    from ``reset(seed=0)``, read off each row's state around each step (the env is
    deterministic: the timed runs made the same): a test update per test; a learning update
    for the batch under way before a test or a fitting (a replacement or a failure) and for
    each full batch; a RUL-table rebuild per row flagged stale when the observation is made.
    Each row's batch count is followed through the step and must land on the env's (an
    ``AssertionError`` otherwise: the rules above missed an update); the rules assume one
    flight per slot (the single actuator's env), and leave out the prediction a reset makes
    for parts of unknown age (``Scenario.initial_health`` "random" or "in_service"). Each
    part fitting (``scas_env.core.parts.replace_part``, a replacement or a failed part's) is
    counted and its CPU seconds summed: ``fitting``, ``fitting_s`` and ``fitting_learn`` (the
    learning updates fittings made, also in ``learn``) per env-step."""
    env = venv.unwrapped
    interval = int(env.setup.scenario.flight_update_flights)
    env.reset(seed=0)
    total = {"test": 0, "learn": 0, "rebuild": 0, "fitting": 0, "fitting_s": 0.0,
             "fitting_learn": 0}  # fmt: skip
    fit = parts.replace_part

    def timed_fit(*args: Any, **kwargs: Any) -> None:  # each fitting counted, CPU-timed
        t0 = time.process_time()
        fit(*args, **kwargs)
        total["fitting"] += 1
        total["fitting_s"] += time.process_time() - t0

    parts.replace_part = timed_fit
    try:
        _replay(env, actions, interval, total)
    finally:
        parts.replace_part = fit
    steps = (len(actions) - 100) * env.num_envs
    return {k: v / steps for k, v in total.items()}


def _replay(env: Any, actions: np.ndarray, interval: int, total: dict[str, Any]) -> None:
    """:func:`count_updates`' replay (the fittings of the first 100 steps not counted)."""
    a = env.a
    for t, act in enumerate(actions):
        counted = t >= 100
        if t == 100:
            total["fitting"], total["fitting_s"] = 0, 0.0
        moving = ~env._autoreset
        before = {k: a[k].copy() for k in ("flight_count", "tests", "flown", "failures")}
        env.step_active(act, None, outputs=False)
        if counted:
            total["rebuild"] += int(a["stale"].sum())
        env.observe()
        tested = (a["tests"] - before["tests"])[moving]
        flew = (a["flown"] - before["flown"])[moving]
        failed = (a["failures"] - before["failures"]).sum(axis=1)[moving] > 0
        refit = (act[moving] >= 2) | failed
        count = before["flight_count"][moving].copy()
        learns = np.zeros(count.size, dtype=np.int64)
        first = (tested > 0) & (count > 0)  # a test learns the batch under way first
        learns += first
        count[tested > 0] = 0
        count += flew
        full = count >= interval
        learns += full
        count[full] = 0
        fitting = refit & (count > 0)  # a fitting learns it too
        learns += fitting
        count[refit] = 0
        assert np.array_equal(count, a["flight_count"][moving]), "an update was missed"
        if counted:
            total["test"] += int(tested.sum())
            total["learn"] += int(learns.sum())
            total["fitting_learn"] += int(fitting.sum())


@njit(cache=True)
def _time_learn(rows, bank, pending, flight_sum, flight_count, usage, status, filt, handles,
                interval, means):  # fmt: skip
    work = work_arrays(bank[0].shape[2], flight_sum.shape[1])
    for e in rows:
        flight_count[e] = interval
        usage[e, 0] = float(interval)
        usage[e, 1] = float(interval)
        pending[e, 0] = float(interval)
        pending[e, 1] = float(interval)
        for j in range(flight_sum.shape[1]):
            flight_sum[e, j] = means[e, j] * interval
        h = (handles[e, 0], handles[e, 1], handles[e, 2])
        learn_row(e, bank, pending, flight_sum, flight_count, usage, status, work, filt, h)


@njit(cache=True)
def _time_test(rows, bank, pending, flight_sum, flight_count, usage, status, filt, handles,
               ground):  # fmt: skip
    work = work_arrays(bank[0].shape[2], flight_sum.shape[1])
    for e in rows:
        flight_count[e] = 0
        pending[e, 0] = 10.0
        pending[e, 1] = 10.0
        h = (handles[e, 0], handles[e, 1], handles[e, 2])
        test_row(e, ground[e, 0], ground[e, 1], bank, pending, flight_sum, flight_count, usage,
                 status, work, filt, h)  # fmt: skip


@njit(cache=True)
def _time_rebuild(rows, bank, tables, status, filt):  # fmt: skip
    work = work_arrays(bank[0].shape[2], filt.learn_part.size)
    for e in rows:
        refresh_row(e, bank, tables, status, work, filt)


def update_costs(venv: Any, repeats: int = 20) -> dict[str, float]:
    """CPU seconds of one test update, one learning update and one RUL-table rebuild (both
    parts), each alone on the batch of ``venv`` after 100 flying slots, averaged over its
    rows: the best of three sums of ``repeats`` timed calls, every call (warm-up included)
    from that state, restored before it (an update changes the clouds, so a call after
    others would time clouds the env never holds there)."""
    env = venv.unwrapped
    env.reset(seed=0)
    for _ in range(100):
        env.step(np.zeros(env.num_envs, dtype=np.int64))
    batch = env.batch
    a, st = batch.a, batch.setup
    # every array the kernels change is one of these (their arguments are views of them)
    state = [v for v in a.values() if isinstance(v, np.ndarray)]
    snapshot = [v.copy() for v in state]

    def from_state(fn: Callable[[], Any]) -> float:
        """CPU seconds of ``fn`` called once from the state after the 100 slots."""
        for v, saved in zip(state, snapshot, strict=True):
            np.copyto(v, saved)
        return _cpu(fn)

    rows = np.arange(batch.n, dtype=np.int64)
    last = a["last"]
    means = last[:, st.learn_cols].copy()
    ground = last[:, len(st.world.flight_idx) :].copy()
    args = (rows, batch.bank, a["pending"], a["flight_sum"], a["flight_count"],
            a["batch_usage"], a["status"], st.filters, a["h_filter"])  # fmt: skip
    interval = int(st.scenario.flight_update_flights)
    rebuild = (rows, batch.bank, batch.tables, a["status"], st.filters)
    kinds = {
        "test": lambda: _time_test(*args, ground),
        "learn": lambda: _time_learn(*args, interval, means),
        "rebuild": lambda: _time_rebuild(*rebuild),
    }
    out = {}
    for name, fn in kinds.items():
        from_state(fn)
        out[name] = _best(lambda fn=fn: sum(from_state(fn) for _ in range(repeats)))
        out[name] /= rows.size * repeats
    return out


def fleet_rates(episodes: int = 2) -> dict[str, float]:
    """The default fleet under the naive rule: actuator-flights per second, seconds per
    episode (CPU)."""
    import policies  # noqa: F401  (registers the rules)
    from policies.base import make_policy

    env = gym.make(scas_env.ENV_ID_FLEET)
    u = env.unwrapped
    policy = make_policy("fleet_naive", u.obs_names)
    actuators = u.fleet.shape.actuators
    out = []
    for seed in range(episodes + 1):
        obs, _ = env.reset(seed=seed)

        def go() -> int:
            nonlocal obs
            done = False
            while not done:
                obs, _, te, tr, info = env.step(policy.predict(obs)[0])
                done = te or tr
            return int(info["flights"])

        t0 = time.process_time()
        flights = go()
        out.append((time.process_time() - t0, flights * actuators))
    secs = [s for s, _ in out[1:]]  # the first compiles
    flights = [f for _, f in out[1:]]
    return {
        "fleet_episode_s": float(np.mean(secs)),
        "fleet_actuator_flights_per_s": float(np.sum(flights) / np.sum(secs)),
    }


def measure() -> dict[str, float]:
    """Every figure of the module docstring, in one run."""
    out = {**single_env_us(), **vector_rates(), **fleet_rates()}
    out["fleet_share_of_vector"] = out["fleet_actuator_flights_per_s"] / out["mix_steps_per_s"]
    return out


#: the figures :func:`compare` times, and whether more is faster
COMPARED = {"fly_us": False, "test_every_10_us": False, "mix_steps_per_s": True,
            "fly_steps_per_s": True}  # fmt: skip


def compare(fields: dict[str, Any], repeats: int = 2) -> dict[str, dict[str, float]]:
    """The single and vector env figures (:data:`COMPARED`) with the default scenario and
    with ``fields``, alternated ``repeats`` times in one run: per figure the best of each
    and the slowdown (the option's time per step over the default's)."""
    best: dict[str, dict[str, float]] = {"default": {}, "option": {}}
    for _ in range(repeats):
        for name, kw in (("default", {}), ("option", fields)):
            figures = {**single_env_us(**kw), **vector_rates(**kw)}
            for k, faster in COMPARED.items():
                old = best[name].get(k)
                new = figures[k]
                best[name][k] = new if old is None else (max if faster else min)(old, new)
    best["slowdown"] = {
        k: (best["default"][k] / best["option"][k] if faster else best["option"][k]
            / best["default"][k])
        for k, faster in COMPARED.items()
    }  # fmt: skip
    return best


def format_comparison(c: dict[str, dict[str, float]], fields: dict[str, Any]) -> str:
    lines = [f"default scenario vs {json.dumps(fields)} (best of each, CPU time; slowdown = "
             "time per step with the option / without)"]  # fmt: skip
    for k in COMPARED:
        d, o, s = c["default"][k], c["option"][k], c["slowdown"][k]
        lines.append(f"{k:20s} {d:12,.1f} {o:12,.1f}   slowdown x{s:.3f}")
    return "\n".join(lines)


def format_rates(r: dict[str, float]) -> str:
    return "\n".join(
        [
            f"single env, flying:           {r['fly_us']:8.1f} us/step "
            f"(CartPole-v1 {r['cartpole_us']:.1f} us: x{r['fly_us'] / r['cartpole_us']:.1f})",
            f"single env, test every 10:    {r['test_every_10_us']:8.1f} us/step "
            f"(x{r['test_every_10_us'] / r['cartpole_us']:.1f} CartPole)",
            f"vector env 64, mix 90/9/1:    {r['mix_steps_per_s']:10,.0f} env-steps/s "
            f"(CartPole vector {r['cartpole_vector_steps_per_s']:,.0f})",
            f"vector env 64, flying:        {r['fly_steps_per_s']:10,.0f} env-steps/s",
            f"filter updates of the mix:    {r['tests_per_step']:.3f} tests, "
            f"{r['learns_per_step']:.3f} learning updates and {r['rebuilds_per_step']:.3f} RUL "
            f"rebuilds per step; {r['test_update_us']:.1f}, {r['learn_update_us']:.1f} and "
            f"{r['rebuild_us']:.1f} us each",
            f"filter arithmetic ceiling:    {r['filter_ceiling_steps_per_s']:10,.0f} env-steps/s "
            f"(the mix reaches {100 * r['share_of_ceiling']:.0f} %)",
            f"a step's flight, obs and info: {r['fly_other_us']:8.1f} us (flying alone, less "
            f"its updates): with them the mix could reach at most "
            f"{100 * r['share_cap_with_flight']:.0f} % of the ceiling",
            f"fitting a part in the mix:     {r['fitting_us']:8.1f} us each (its learning update "
            f"included), {r['fitting_us_per_step']:.2f} us per env-step, "
            f"{r['fitting_net_us_per_step']:.2f} without its learning updates",
            f"fleet (8 x 3, naive rule):    {r['fleet_actuator_flights_per_s']:10,.0f} "
            f"actuator-flights/s ({100 * r['fleet_share_of_vector']:.0f} % of the vector env's "
            f"actuator-steps/s), {r['fleet_episode_s']:.2f} s per 365-day episode",
        ]
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=None, help="also write the figures here")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --json")
    parser.add_argument(
        "--scenario",
        type=json.loads,
        default=None,
        help="compare the single and vector env with these Scenario fields (JSON) against "
        "the defaults, in one run (module docstring)",
    )
    args = parser.parse_args(argv)
    if args.json is not None and args.json.exists() and not args.overwrite:
        parser.error(f"--json {args.json} exists; pass --overwrite to replace it")
    if args.scenario is not None:
        result = compare(args.scenario)
        print(format_comparison(result, args.scenario))
        if args.json is not None:
            write_text_atomic(args.json, json_text(result, indent=1))
        return 0
    rates = measure()
    print(format_rates(rates))
    if args.json is not None:
        write_text_atomic(args.json, json_text(rates, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
