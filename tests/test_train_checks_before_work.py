"""``scas-train`` and :func:`policies.agents.training.train_epochs` check everything before
any folder or env is made: a bad search file, candidate, algorithm keyword, schedule, range,
seed, wall-clock limit, or a warm start whose network or statistics do not fit is a usage
error (exit 2, one line naming the value) and ``--out`` is not created, so the corrected
rerun is not refused. ``--checkpoint-every`` is rounded down to a multiple of the env count,
as documented and logged."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest
import yaml

from policies.agents import training
from policies.cli import train as train_cli

BASE = training.HYPERPARAMS_DIR / "maskable_ppo.yml"


def _search(tmp: Path, text: str) -> Path:
    path = tmp / f"search_{abs(hash(text))}.yml"
    path.write_text(text)
    return path


def _candidate(tmp: Path, overrides: dict) -> list[str]:
    spec = {"base": str(BASE), "candidates": {"c": overrides}}
    return ["--search", str(_search(tmp, yaml.safe_dump(spec))), "--candidate", "c"]


def _usage_error(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as exit_:
        train_cli.main(argv)
    err = capsys.readouterr().err
    assert exit_.value.code == 2, err
    assert "Traceback" not in err and "error:" in err
    return " ".join(err.split())


@pytest.fixture(scope="module")
def init_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A warm-start folder of the base candidate's network (``model.zip``) and statistics
    of its ``gamma`` (``normalization.json``), made as a clone's are."""
    tmp = tmp_path_factory.mktemp("init")
    hp = training.candidate_hyperparams(training.HYPERPARAMS_DIR / "search.yml", "gamma099")
    model, venv, *_ = training.prepared_run(
        hp,
        tmp / "made",
        seed=0,
        algo="maskable_ppo",
        ks=training.DEFAULT_KS,
        native_envs=None,
        scenario={},
    )
    init = tmp / "clone"
    init.mkdir()
    model.save(init / "model.zip")
    training.save_statistics(venv, init / training.NORMALIZATION_FILE)
    venv.close()
    return init


def test_bad_search_files_and_keywords_are_usage_errors_and_out_is_not_made(
    tmp_path: Path, init_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    init = ["--init", str(init_dir)]

    def search(text: str) -> list[str]:
        return ["--search", str(_search(tmp_path, text)), "--candidate", "c"]

    def cand(overrides: dict, *more: str) -> list[str]:
        return [*_candidate(tmp_path, overrides), *more]

    cases = [
        (search("foo: [\n"), "not valid YAML"),
        (search("base: x.yml\ncandidates:\n  c: 0.99\n"), "candidate 'c' = 0.99 must be a map"),
        (search("candidates:\n  c: {gamma: 0.99}\n"), "base = None; it needs 'base: <file>.yml'"),
        (cand({"n_step": 64}), "['n_step'] are not MaskablePPO keywords"),
        (cand({"learning_rate": "lin_abc"}), "learning_rate = 'lin_abc'"),
        (cand({"gamma": 1.5}), "gamma = 1.5 must be in (0, 1]"),
        (cand({"gamma": 0.0}), "gamma = 0.0 must be in (0, 1]"),
        (cand({"learning_rate": -1e-4}), "learning_rate = -0.0001 must be >= 0"),
        (cand({"n_steps": 0}), "n_steps = 0 must be an integer >= 1"),
        (cand({"batch_size": 64.5}), "batch_size = 64.5 must be an integer >= 1"),
        (cand({"gae_lambda": "high"}), "gae_lambda = 'high' must be a finite number"),
        (cand({"seed": 3}), "['seed']: set by train_epochs"),
        (
            cand({"reference_mix": 0.05}, "--algo", "ppo", *init),
            "reference_mix needs policy 'MlpPolicy' and algo 'maskable_ppo'",
        ),
        (cand({"reference_mix": 2.0}, *init), "reference_mix = 2.0 must be a number in (0, 1]"),
        (["--seed", str(2**32)], f"seed = {2**32} must be an integer in [0, 2**32)"),
        (cand({"policy_kwargs": {"net_arch": [32]}}, *init), "its network does not match"),
        (
            cand({"gamma": 0.5}, *init),
            "the return statistics are of gamma = 0.99; the VecNormalize has gamma = 0.5",
        ),
    ]
    for argv, message in cases:
        err = _usage_error([*argv, "--out", str(out)], capsys)
        assert message in err, (argv, err)
        assert not out.exists(), argv


def test_the_api_refuses_a_bad_seed_or_wall_clock_before_any_folder(tmp_path: Path) -> None:
    hp = training.candidate_hyperparams(training.HYPERPARAMS_DIR / "search.yml", "gamma099")
    cases = [
        ({"max_wall_s": "10"}, "max_wall_s = '10' must be a finite number > 0"),
        ({"max_wall_s": -1.0}, "max_wall_s = -1.0 must be a finite number > 0"),
        ({"max_wall_s": float("inf")}, "max_wall_s = inf must be a finite number > 0"),
        ({"max_wall_s": True}, "max_wall_s = True must be a finite number > 0"),
        ({"seed": -1}, r"seed = -1 must be an integer in [0, 2**32)"),
        ({"seed": 1.5}, r"seed = 1.5 must be an integer in [0, 2**32)"),
        ({"seed": True}, r"seed = True must be an integer in [0, 2**32)"),
        ({"seed": 2**32}, rf"seed = {2**32} must be an integer in [0, 2**32)"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError) as err:
            training.train_epochs(hp, tmp_path / "o", total_timesteps=32, **kwargs)
        assert message in str(err.value)
        assert not (tmp_path / "o").exists()
    for name in ("search.yml",):  # every shipped candidate passes the new checks
        spec = yaml.safe_load((training.HYPERPARAMS_DIR / name).read_text())
        for candidate in spec["candidates"]:
            hp = training.candidate_hyperparams(training.HYPERPARAMS_DIR / name, candidate)
            training.run_settings(hp, "maskable_ppo")


def test_checkpoints_are_every_multiple_of_the_env_count_below_the_request(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SB3 saves every ``checkpoint_every // n_envs`` steps of all envs: the interval is the
    largest multiple of ``n_envs`` not above the request (at least ``n_envs``), and
    ``scas-train`` says so."""
    for every, n in ((500_000, 64), (25_000, 4), (10, 64), (128, 2), (129, 2)):
        want = n * max(1, every // n)
        assert training.checkpoint_interval(every, n) == want
        assert want <= max(every, n) and want % n == 0 and want + n > every
    calls = []
    monkeypatch.setattr(training, "train_epochs", lambda *a, **k: calls.append(k) or "x")
    caplog.set_level(logging.INFO, logger="policies.cli.train")
    argv = ["--native-envs", "64", "--checkpoint-every", "500000"]
    assert train_cli.main([*argv, "--out", str(tmp_path / "o")]) == 0
    assert calls and calls[0]["checkpoint_every"] == 500_000
    assert (
        "a checkpoint every 499,968 decisions: 500,000 rounded down to a multiple of 64 envs"
        in (caplog.text)
    )
    help_text = " ".join(train_cli.build_parser().format_help().split())
    assert "rounded down to a multiple of the env count" in help_text
