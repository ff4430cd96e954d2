"""The batched filter kernels on several threads give the serial kernels' numbers bit for bit.

``ScasMaintenanceVectorEnv(kernel_threads=T)`` splits the rows of each
:func:`~scas_env.learning_kernel.test_batch`, ``learn_batch`` and ``refresh_tables`` call
into chunks run in parallel (``*_threads`` kernels). Here a vector env with T threads and
one with 1 are stepped with the same actions over a mix with many tests, some replacements
and episode ends, and everything they output or keep is compared bit for bit: observations,
rewards, terminations, infos, the fleet's arrays, the particle bank and every actuator's
filter random stream (the same draws were taken from each). T = 3 forces three chunks per
call (this machine's numba may run fewer threads: the chunks are then shared out), so the
chunks are uneven; T = 2 uses the env's own choice of chunks, and the test checks that
parallel calls happened.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import subprocess
import sys
import warnings
from collections import Counter
from pathlib import Path
from typing import Any

import numba
import numpy as np
import pytest

from scas_env import V2_KWARGS, learning_kernel
from scas_env import vector_env as vector_env_module
from scas_env.decision_epochs_vector import DecisionEpochsVectorEnv
from scas_env.learning_kernel import chunk_bounds, chunk_count
from scas_env.utils.parallel import single_threaded
from scas_env.vector_env import ScasMaintenanceVectorEnv, make_vector_env

_KW = {**V2_KWARGS, "initial_health": "random", "episode_slots": 120}
#: (fly, test_and_fly, replace_spring, replace_seal): many tests, some replacements
_MIX = [0.6, 0.36, 0.02, 0.02]
#: mostly flights: full in-flight batches of many actuators at once
_FLY_MOSTLY = [0.95, 0.03, 0.01, 0.01]


def assert_bits_equal(a: Any, b: Any, where: str) -> None:
    """``a`` and ``b`` equal bit for bit (arrays: dtype, shape and bytes; dicts, tuples and
    lists element-wise; anything else ``==``)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), where
        for k in a:
            assert_bits_equal(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray), where
        assert (a.dtype, a.shape) == (b.dtype, b.shape), where
        if a.dtype == object:
            for i, (x, y) in enumerate(zip(a.ravel(), b.ravel(), strict=True)):
                assert_bits_equal(x, y, f"{where}.flat[{i}]")
        else:
            assert np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes(), where
    elif isinstance(a, tuple | list):
        assert type(a) is type(b) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_bits_equal(x, y, f"{where}[{i}]")
    else:
        assert type(a) is type(b), where
        assert a == b or (a != a and b != b), where  # NaN == NaN here


def _assert_states_equal(threaded: ScasMaintenanceVectorEnv, serial: ScasMaintenanceVectorEnv,
                         where: str) -> None:  # fmt: skip
    """The fleet arrays, the bank's particles and each actuator's filter stream."""
    assert_bits_equal(dict(threaded.a.items()), dict(serial.a.items()), f"{where}: fleet")
    assert_bits_equal(threaded._learn_out, serial._learn_out, f"{where}: kernel outputs")
    assert_bits_equal(threaded._stale, serial._stale, f"{where}: stale tables")
    assert_bits_equal(threaded._bank.arrays, serial._bank.arrays, f"{where}: bank")
    for e, (x, y) in enumerate(zip(threaded.envs, serial.envs, strict=True)):
        gx = x.monitor.spring_filter._stream.rng.bit_generator.state
        gy = y.monitor.spring_filter._stream.rng.bit_generator.state
        assert gx == gy, f"{where}: filter stream of actuator {e}"


@pytest.fixture
def kernel_spy(monkeypatch: pytest.MonkeyPatch):
    """Count the vector env's calls of each threaded kernel by its number of chunks;
    ``force=T``: an env with ``kernel_threads`` > 1 uses min(T, rows) chunks whatever numba's
    thread count (uneven chunks on any machine); a serial env stays serial."""
    calls: Counter = Counter()

    def install(force: int | None) -> Counter:
        def chunks(n_rows: int, threads: int) -> int:
            if force is None or threads == 1:
                return chunk_count(n_rows, threads)
            return max(1, min(force, n_rows))

        monkeypatch.setattr(vector_env_module, "chunk_count", chunks)
        for name in ("learn_batch_threads", "test_batch_threads", "refresh_tables_threads"):
            kernel = getattr(vector_env_module, name)

            def counted(*args: Any, kernel: Any = kernel, name: str = name) -> None:
                calls[name, args[-1]] += 1
                kernel(*args)

            monkeypatch.setattr(vector_env_module, name, counted)
        return calls

    return install


def _threaded_calls(calls: Counter, kernel: str) -> int:
    return sum(n for (name, k), n in calls.items() if name == kernel and k > 1)


def _actions(rng: np.random.Generator, t: int, n: int) -> np.ndarray:
    """Many tests (batched test updates) for 150 steps, then mostly flights (in-flight
    learning updates of many actuators at once)."""
    return rng.choice(4, size=n, p=_MIX if t < 150 else _FLY_MOSTLY)


@pytest.mark.parametrize("threads, force", [(2, None), (3, 3)])
def test_threads_give_the_serial_numbers(kernel_spy, threads: int, force: int | None) -> None:
    if force is None and numba.get_num_threads() < 2:
        pytest.skip("numba runs one thread here: the env would call the serial kernels")
    calls = kernel_spy(force)
    n = 48
    threaded = ScasMaintenanceVectorEnv(n, kernel_threads=threads, **_KW)
    serial = ScasMaintenanceVectorEnv(n, **_KW)
    assert serial.kernel_threads == 1 and threaded.kernel_threads == threads
    assert_bits_equal(threaded.reset(seed=5), serial.reset(seed=5), "reset")
    rng = np.random.default_rng(11)
    ends = 0
    for t in range(300):
        actions = _actions(rng, t, n)
        out_t, out_s = threaded.step(actions), serial.step(actions)
        assert_bits_equal(out_t, out_s, f"step {t}")
        ends += int(np.sum(out_s[2] | out_s[3]))
        if t % 50 == 49:
            _assert_states_equal(threaded, serial, f"step {t}")
    _assert_states_equal(threaded, serial, "end")
    assert ends >= n  # autoresets (new filters attached to the bank) happened
    # both threaded kernels ran, many times (the serial env never calls them)
    assert _threaded_calls(calls, "test_batch_threads") >= 100, calls
    assert _threaded_calls(calls, "learn_batch_threads") >= 20, calls
    if force is not None:
        assert calls["test_batch_threads", 3] > 0 and calls["learn_batch_threads", 3] > 0


def test_a_pickled_threaded_env_continues_with_the_serial_numbers(kernel_spy) -> None:
    calls = kernel_spy(3)
    n = 24
    threaded = ScasMaintenanceVectorEnv(n, kernel_threads=3, **_KW)
    serial = ScasMaintenanceVectorEnv(n, **_KW)
    threaded.reset(seed=9)
    serial.reset(seed=9)
    rng = np.random.default_rng(1)
    for t in range(60):
        actions = _actions(rng, t, n)
        threaded.step(actions)
        serial.step(actions)
    copy = pickle.loads(pickle.dumps(threaded))
    assert copy.kernel_threads == 3
    for t in range(60):
        actions = _actions(rng, 150 + t, n)
        assert_bits_equal(copy.step(actions), serial.step(actions), f"after pickling, {t}")
    _assert_states_equal(copy, serial, "end")
    assert _threaded_calls(calls, "learn_batch_threads") >= 5, calls


def test_an_env_pickled_before_the_option_loads_serial() -> None:
    env = ScasMaintenanceVectorEnv(2, **_KW)
    env.reset(seed=0)
    del env.kernel_threads, env._stale_tables.kernel_threads  # as pickled before the option
    old = pickle.loads(pickle.dumps(env))
    assert old.kernel_threads == 1 and old._stale_tables.kernel_threads == 1
    old.step(np.ones(2, dtype=np.int64))


def _python(code: str, **env: str) -> subprocess.CompletedProcess:
    environ = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
        env={**environ, "PYTHONPATH": str(Path(__file__).parents[1]), **env},
    )  # fmt: skip


_MAKE_THREADED = (
    "import os, warnings\n"
    "warnings.simplefilter('always')\n"
    "from scas_env import V2_KWARGS\n"
    "from scas_env.vector_env import ScasMaintenanceVectorEnv\n"
    "ScasMaintenanceVectorEnv(2, kernel_threads=2, **V2_KWARGS)\n"
    "print('policy', os.environ.get('OMP_WAIT_POLICY'))\n"
)


def test_threads_start_with_a_passive_openmp_wait() -> None:
    """A threaded env starts numba's threads with OMP_WAIT_POLICY=PASSIVE unless set; with
    torch imported first (its libgomp runs numba's regions) it warns, unless the policy was
    set before."""
    plain = _python(_MAKE_THREADED)
    assert plain.returncode == 0, plain.stderr
    assert "policy PASSIVE" in plain.stdout and "OMP_WAIT_POLICY" not in plain.stderr
    mine = _python(_MAKE_THREADED, OMP_WAIT_POLICY="ACTIVE")
    assert "policy ACTIVE" in mine.stdout and "OMP_WAIT_POLICY" not in mine.stderr
    pytest.importorskip("torch")
    late = _python("import torch\n" + _MAKE_THREADED)
    assert late.returncode == 0, late.stderr
    assert "torch imported before OMP_WAIT_POLICY was set" in late.stderr
    early = _python("import torch\n" + _MAKE_THREADED, OMP_WAIT_POLICY="PASSIVE")
    assert early.returncode == 0 and "OMP_WAIT_POLICY" not in early.stderr, early.stderr


def test_stale_tables_refreshed_on_threads(kernel_spy) -> None:
    """The decision-epoch vector env (learning updates leave stale RUL tables, rebuilt by
    ``refresh_tables_threads`` on read) with 3 forced chunks against the serial one."""
    calls = kernel_spy(3)
    n = 12
    threaded = DecisionEpochsVectorEnv(n, kernel_threads=3, **_KW)
    serial = DecisionEpochsVectorEnv(n, **_KW)
    assert threaded.inner.kernel_threads == 3
    assert_bits_equal(threaded.reset(seed=2), serial.reset(seed=2), "reset")
    rng = np.random.default_rng(4)
    for t in range(80):
        masks = serial.action_masks()
        assert_bits_equal(threaded.action_masks(), masks, f"masks {t}")
        actions = np.array([rng.choice(np.flatnonzero(m)) for m in masks])
        assert_bits_equal(threaded.step(actions), serial.step(actions), f"decision {t}")
    _assert_states_equal(threaded.inner, serial.inner, "end")
    assert _threaded_calls(calls, "refresh_tables_threads") >= 10, calls
    assert _threaded_calls(calls, "learn_batch_threads") >= 10, calls


def test_make_vec_passes_kernel_threads() -> None:
    import gymnasium as gym

    from scas_env import ENV_ID_EPOCHS_V2, ENV_ID_V2

    envs = gym.make_vec(
        ENV_ID_V2, num_envs=2, vectorization_mode="vector_entry_point", kernel_threads=2
    )
    assert envs.unwrapped.kernel_threads == 2
    epochs = gym.make_vec(
        ENV_ID_EPOCHS_V2, num_envs=2, vectorization_mode="vector_entry_point", kernel_threads=2
    )
    assert epochs.unwrapped.inner.kernel_threads == 2
    physics = make_vector_env(1, fidelity="physics", kernel_threads=2)
    assert physics.kernel_threads == 2


@pytest.mark.parametrize("bad", [0, -1, 1.5, 2.0, "2", True, None])
def test_bad_kernel_threads_raise_naming_the_value(bad: Any) -> None:
    with pytest.raises(ValueError, match=rf"kernel_threads = {bad!r} must be an integer >= 1"):
        ScasMaintenanceVectorEnv(2, kernel_threads=bad, **_KW)
    with pytest.raises(ValueError, match=rf"kernel_threads = {bad!r} must be"):
        make_vector_env(1, fidelity="physics", kernel_threads=bad)


def test_chunk_bounds_cover_the_rows_in_order() -> None:
    for n_rows in range(12):
        for n_chunks in range(1, 5):
            b = chunk_bounds(n_rows, n_chunks)
            sizes = np.diff(b)
            assert b[0] == 0 and b[-1] == n_rows and np.all(sizes >= 0)
            assert sizes.max() - sizes.min() <= 1, (n_rows, n_chunks, b)


def test_chunk_count_respects_numba_threads() -> None:
    least = learning_kernel.MIN_ROWS_PER_CHUNK
    assert chunk_count(64, 1) == 1
    assert chunk_count(2 * least - 1, 4) == 1  # too few rows for two chunks: serial
    with single_threaded():  # a worker's settings: numba.set_num_threads(1)
        assert chunk_count(64, 4) == 1
    available = numba.get_num_threads()
    assert chunk_count(64 * least, 64) == available
    if available >= 2:
        numba.set_num_threads(2)
        try:
            assert chunk_count(64, 8) == 2 and chunk_count(2 * least, 2) == 2
            assert chunk_count(3 * least - 1, 3) == 2  # at least `least` rows a chunk
        finally:
            numba.set_num_threads(available)


def _child_rewards(queue: Any) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rewards = _rewards(kernel_threads=2)
    queue.put((rewards, [str(w.message) for w in caught]))


def _rewards(kernel_threads: int) -> list[float]:
    env = ScasMaintenanceVectorEnv(8, kernel_threads=kernel_threads, **_KW)
    env.reset(seed=1)
    rng = np.random.default_rng(0)
    return [env.step(rng.choice(4, size=8, p=_MIX))[1].tolist() for _ in range(40)]


@pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(), reason="no fork start method"
)
def test_forked_child_of_gnu_openmp_runs_the_serial_kernels() -> None:
    """libgomp is not fork-safe (numba kills a forked child entering a parallel region once
    the parent ran one): such a child runs the serial kernels, warns, and gets the numbers."""
    expected = _rewards(kernel_threads=2)  # the parent runs the threaded kernels
    if not learning_kernel._gnu_openmp_running():
        pytest.skip("numba's threading layer here is not GNU OpenMP")
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_child_rewards, args=(queue,))
    child.start()
    child.join(120)
    assert child.exitcode == 0
    rewards, messages = queue.get(timeout=5)
    assert rewards == expected
    assert any("forked from one running numba's threads on GNU OpenMP" in m for m in messages)


def test_sb3_speed_setup_with_two_kernel_threads() -> None:
    """``epochs-native-64-t2`` is ``epochs-native-64`` with the filter kernels on 2 threads."""
    from experiments.sb3_speed import make_setup

    def inner(venv: Any) -> Any:
        while hasattr(venv, "venv"):
            venv = venv.venv
        return venv.unwrapped.inner

    one, two = make_setup("epochs-native-64"), make_setup("epochs-native-64-t2")
    assert (inner(one).kernel_threads, inner(two).kernel_threads) == (1, 2)
    assert one.num_envs == two.num_envs == 64
    one.close()
    two.close()
