"""Outputs of the paper commands (experiments.paper): results folders with a manifest that
``--overwrite`` replaces, campaign stems with dots, saved-campaign checks, preset tables,
the analysed campaign's identity in the report and Fig. 8's wear axis."""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any

import pytest

from experiments.paper import demo, figures, reproduction_report
from experiments.paper.campaign import CampaignConfig, run_campaign
from experiments.paper.campaign_table import campaign_paths, load
from experiments.paper.reproduction import ReproductionConfig, run_reproduction
from scas_env.actuator.health import HealthState
from scas_env.actuator.params import ScasParams
from scas_env.utils.results_folder import (
    MANIFEST,
    ResultsFolderExistsError,
    verify_results_folder,
)

P = ScasParams()
STATES = {"healthy": HealthState(), "cracked": HealthState(crack_depth_m=0.5e-3)}
CAMPAIGN_SEED = 7


class Interrupted(Exception):
    """Stands for Ctrl-C / a crash in the middle of writing a results folder."""


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def _siblings(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.parent.iterdir())


# --- A: demo, figures and reproduce write results folders ---------------------------------
def test_demo_overwrites_its_own_folder_and_an_interrupted_run_keeps_the_old(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "demo"
    first = demo.run_demo(P, out, 5, STATES, window_s=1.0, progress=False)
    assert verify_results_folder(out) == sorted(
        [f"{s}_{c}.csv" for s in STATES for c in demo.CONDITIONS] + ["flight.png", "preflight.png"]
    )
    assert json.loads((out / MANIFEST).read_text())["seeds"] == {"root": 5}
    assert [r.csv_path for r in first.rows] == [
        out / f"{s}_{c}.csv" for s in STATES for c in demo.CONDITIONS
    ]
    before = _snapshot(out)
    with pytest.raises(ResultsFolderExistsError, match="already exists and is not empty"):
        demo.run_demo(P, out, 6, STATES, window_s=1.0, progress=False)
    assert _snapshot(out) == before
    second = demo.run_demo(P, out, 6, STATES, window_s=1.0, progress=False, overwrite=True)
    assert json.loads((out / MANIFEST).read_text())["seeds"] == {"root": 6}
    assert second.rows[1].csv_path.read_bytes() != before[second.rows[1].csv_path.name]
    replaced = _snapshot(out)

    def broken(*args: Any, **kwargs: Any) -> None:
        raise Interrupted

    monkeypatch.setattr(demo, "plot_demo_condition", broken)
    with pytest.raises(Interrupted):
        demo.run_demo(P, out, 7, STATES, window_s=1.0, progress=False, overwrite=True)
    assert _snapshot(out) == replaced  # the old complete folder, no new CSV in it
    assert _siblings(out) == ["demo"]  # no partial folder left beside it


def test_demo_command_runs_twice_with_overwrite_and_refuses_without(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = str(tmp_path / "runs" / "demo")
    for _ in range(2):
        assert demo.main(["--window", "1", "--out", out, "--overwrite"]) == 0
        verify_results_folder(out)
    capsys.readouterr()
    with pytest.raises(SystemExit) as stop:
        demo.main(["--window", "1", "--out", out])
    assert stop.value.code == 2
    assert f"--out {out} already exists and is not empty; pass --overwrite" in (
        capsys.readouterr().err
    )


class _FakeFigures:
    def __init__(self, value: int) -> None:
        self.value = value
        for name in figures.PAPER_PLOTS:
            setattr(self, name, value)

    def to_dict(self) -> dict[str, int]:
        return {"value": self.value}


def _fake_plot(data: int, path: Path) -> None:
    Path(path).write_text(f"figure {data}\n")


def test_paper_figures_overwrite_their_own_folder_and_an_interrupted_run_keeps_the_old(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    plots = {name: (stem, _fake_plot) for name, (stem, _) in figures.PAPER_PLOTS.items()}
    monkeypatch.setattr(figures, "PAPER_PLOTS", plots)
    out = tmp_path / "figures"
    paths = figures.save_paper_figures(_FakeFigures(1), out, seed=3)  # type: ignore[arg-type]
    names = sorted([f"{stem}.png" for stem, _ in plots.values()] + ["figures.json"])
    assert sorted(p.name for p in paths) == names and all(p.parent == out for p in paths)
    assert verify_results_folder(out) == names
    assert json.loads((out / MANIFEST).read_text())["seeds"] == {"fig4": 3}
    with pytest.raises(ResultsFolderExistsError, match="already exists and is not empty"):
        figures.save_paper_figures(_FakeFigures(2), out)  # type: ignore[arg-type]
    figures.save_paper_figures(_FakeFigures(2), out, overwrite=True)  # type: ignore[arg-type]
    assert json.loads((out / "figures.json").read_text()) == {"value": 2}
    replaced = _snapshot(out)

    def broken(data: int, path: Path) -> None:
        raise Interrupted

    first = next(iter(plots))
    monkeypatch.setitem(plots, first, (plots[first][0], broken))
    with pytest.raises(Interrupted):
        figures.save_paper_figures(_FakeFigures(3), out, overwrite=True)  # type: ignore[arg-type]
    assert _snapshot(out) == replaced
    assert _siblings(out) == ["figures"]


@pytest.fixture(scope="module")
def saved_campaign(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small campaign of seed 7 saved under a stem with a dot."""
    stem = tmp_path_factory.mktemp("camp") / "small_0.5"
    config = CampaignConfig(n_runs=2, n_levels=3, fault_modes=("crack", "wear"))
    run_campaign(P, config, seed=CAMPAIGN_SEED, n_workers=1).save(stem)
    return stem


@pytest.fixture(scope="module")
def small_reproduction(saved_campaign: Path) -> Any:
    config = ReproductionConfig.quick().replace(n_paths=1)
    return run_reproduction(P, config, seed=0, n_workers=1, campaign_path=saved_campaign)


def test_report_overwrites_its_own_folder_and_an_interrupted_run_keeps_the_old(
    small_reproduction: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "reproduction"
    files = reproduction_report.write_report(small_reproduction, out, {"wall_s": 1.0})
    assert sorted(p.name for p in files) == verify_results_folder(out)
    assert all(p.parent == out for p in files) and files[-1] == out / "report.md"
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["seeds"] == {"root": 0, "campaign": CAMPAIGN_SEED}
    with pytest.raises(ResultsFolderExistsError, match="already exists and is not empty"):
        reproduction_report.write_report(small_reproduction, out, {"wall_s": 2.0})
    reproduction_report.write_report(small_reproduction, out, {"wall_s": 2.0}, overwrite=True)
    assert json.loads((out / "report.json").read_text())["wall_s"] == 2.0
    replaced = _snapshot(out)

    def broken(*args: Any, **kwargs: Any) -> None:
        raise Interrupted

    monkeypatch.setattr(reproduction_report, "_ra_plot", broken)
    with pytest.raises(Interrupted):
        reproduction_report.write_report(small_reproduction, out, {"wall_s": 3.0}, overwrite=True)
    assert _snapshot(out) == replaced
    assert _siblings(out) == ["reproduction"]


# --- E: the report names the campaign it analysed -----------------------------------------
def test_report_names_the_analysed_campaigns_seed_path_and_hash(
    small_reproduction: Any, saved_campaign: Path
) -> None:
    csv_path, json_path = campaign_paths(saved_campaign)
    digest = hashlib.sha256(csv_path.read_bytes()).hexdigest()
    assert json.loads(json_path.read_text())["csv_sha256"] == digest
    report = reproduction_report.report_dict(small_reproduction)
    assert report["seed"] == 0
    assert report["campaign"]["seed"] == CAMPAIGN_SEED
    assert report["campaign"]["path"] == str(saved_campaign)
    assert report["campaign"]["csv_sha256"] == digest
    header = reproduction_report._markdown(report).splitlines()[2]
    assert header == (
        f"Seed 0; campaign 2 runs x 3 levels (campaign seed {CAMPAIGN_SEED}, {saved_campaign}, "
        f"CSV SHA-256 {digest}); 1 prognosis path(s) per fault."
    )


# --- H: Fig. 8 for wear is in worn-depth fractions and says so ------------------------------
def test_fig8_wear_axis_and_columns_say_worn_depth_fraction(
    small_reproduction: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    labels: dict[str, str] = {}
    real = reproduction_report.plot_accuracy_sensitivity

    def spy(scores: Any, path: Path, **kwargs: Any) -> Any:
        fig = real(scores, path, **kwargs)
        labels[Path(path).stem] = fig.axes[0].get_xlabel()
        return fig

    monkeypatch.setattr(reproduction_report, "plot_accuracy_sensitivity", spy)
    out = tmp_path / "rep"
    reproduction_report.write_report(small_reproduction, out)
    assert labels == {
        "fig8_crack": "severity at detection",
        "fig8_wear": "worn-depth fraction at detection",
    }
    scores = small_reproduction.selection["scores"]
    for fault, column, top in (
        ("crack", "severity_at_detection", "max_severity"),
        ("wear", "worn_depth_fraction_at_detection", "max_worn_depth_fraction"),
    ):
        lines = (out / f"fig8_{fault}.csv").read_text().splitlines()
        header = lines[0].split(",")
        assert column in header and top in header
        rows = [dict(zip(header, line.split(","), strict=True)) for line in lines[1:]]
        expected = scores[f"{fault}/ground"] + scores[f"{fault}/flight"]
        for row, s in zip(rows, expected, strict=True):  # the numbers are the campaign's
            value = float(row[column])
            assert (math.isnan(value) and math.isnan(s.severity_at_detection)) or (
                value == s.severity_at_detection
            )
            assert float(row[top]) == s.max_severity


# --- B: a campaign stem keeps its dots; files written atomically ----------------------------
def test_campaign_paths_strip_only_a_csv_or_json_suffix(tmp_path: Path) -> None:
    for given in ("c", "c.csv", "c.json", "c.CSV"):
        assert campaign_paths(tmp_path / given) == (tmp_path / "c.csv", tmp_path / "c.json")
    assert campaign_paths(tmp_path / "sweep_temp_0.5") == (
        tmp_path / "sweep_temp_0.5.csv",
        tmp_path / "sweep_temp_0.5.json",
    )
    assert campaign_paths(tmp_path / "t_0.5.csv")[1] == tmp_path / "t_0.5.json"


def test_campaign_command_saves_dotted_stems_side_by_side(tmp_path: Path) -> None:
    from experiments.paper import campaign

    base = ["--runs", "2", "--levels", "2", "--modes", "crack", "--conditions", "ground"]
    for value, seed in (("0.5", "1"), ("0.7", "2")):
        argv = [*base, "--seed", seed, "--workers", "1", "--no-progress"]
        assert campaign.main([*argv, "--out", str(tmp_path / f"sweep_temp_{value}")]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "sweep_temp_0.5.csv",
        "sweep_temp_0.5.json",
        "sweep_temp_0.7.csv",
        "sweep_temp_0.7.json",
    ]
    assert load(tmp_path / "sweep_temp_0.5").metadata["seed"] == 1
    assert load(tmp_path / "sweep_temp_0.7").metadata["seed"] == 2


def test_campaign_save_writes_both_files_atomically(
    saved_campaign: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from experiments.paper import campaign_table

    written: list[str] = []
    real_bytes, real_text = campaign_table.write_bytes_atomic, campaign_table.write_text_atomic

    def record_bytes(path: Path, data: bytes) -> None:
        written.append(Path(path).name)
        real_bytes(path, data)

    def record_text(path: Path, text: str) -> None:
        written.append(Path(path).name)
        real_text(path, text)

    monkeypatch.setattr(campaign_table, "write_bytes_atomic", record_bytes)
    monkeypatch.setattr(campaign_table, "write_text_atomic", record_text)
    result = load(saved_campaign)
    result.save(tmp_path / "copy_0.5")
    assert written == ["copy_0.5.csv", "copy_0.5.json"]
    assert result.csv_sha256 == hashlib.sha256((tmp_path / "copy_0.5.csv").read_bytes()).hexdigest()


# --- C: the detection study refuses campaigns the reproduction refuses ----------------------
@pytest.mark.parametrize(
    ("modes", "levels", "message"),
    [
        (("crack",), 3, "must hold modes ('crack', 'wear') and both conditions, has ['crack']"),
        (("crack", "wear"), 2, "has n_levels = 2; the reproduction needs >= 3"),
    ],
)
def test_detection_command_refuses_an_unusable_campaign(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    modes: tuple[str, ...],
    levels: int,
    message: str,
) -> None:
    from experiments.paper import reproduction_detection

    stem = tmp_path / "c"
    config = CampaignConfig(n_runs=2, n_levels=levels, fault_modes=modes)
    run_campaign(P, config, seed=0, n_workers=1).save(stem)
    argv = ["--campaign", str(stem), "--paths", "2", "--out", str(tmp_path / "d.json")]
    with pytest.raises(SystemExit) as stop:
        reproduction_detection.main([*argv, "--no-progress"])
    assert stop.value.code == 2
    assert f"--campaign: campaign {stem} {message}" in capsys.readouterr().err
    assert not (tmp_path / "d.json").exists()


# --- D: the preset table refuses repeated names and reports without verdicts -------------
def _report_file(path: Path, claims: list[str]) -> str:
    rows = [{"claim": c, "paper": 1, "ours": 2, "verdict": "holds"} for c in claims]
    path.write_text(json.dumps({"verdicts": rows}))
    return str(path)


def test_preset_table_refuses_a_repeated_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from experiments.paper import reproduction_presets

    a = _report_file(tmp_path / "a.json", ["x"])
    b = _report_file(tmp_path / "b.json", ["x"])
    with pytest.raises(SystemExit) as stop:
        reproduction_presets.main([f"paper={a}", f"paper={b}"])
    assert stop.value.code == 2
    assert (
        f"preset name 'paper' is given twice ({a} and {b}); each column needs its own NAME"
        in capsys.readouterr().err
    )
    assert reproduction_presets.main([f"paper={a}", f"realistic={b}"]) == 0
    assert "| result | paper | paper | paper: verdict | realistic | realistic: verdict |" in (
        capsys.readouterr().out
    )


@pytest.mark.parametrize("content", ['{"seed": 0}', "[1, 2]", '{"verdicts": [{"x": 1}]}'])
def test_preset_table_names_a_file_without_verdicts(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str
) -> None:
    from experiments.paper import reproduction_presets

    bad = tmp_path / "other.json"
    bad.write_text(content)
    with pytest.raises(SystemExit) as stop:
        reproduction_presets.main([f"paper={bad}"])
    assert stop.value.code == 2
    assert (
        f"paper={bad} holds no 'verdicts' list of claims; expected the report.json of "
        "python -m experiments.paper.reproduce" in capsys.readouterr().err
    )


# --- I: a path-mean verdict only when its 95 % t-interval is clear --------------------------
def test_interval_verdict_calls_a_verdict_only_when_the_interval_clears_the_threshold() -> None:
    # mean 0.82, sd 0.02, 3 paths: half-width t(0.975, 2) 0.02 / sqrt(3) = 0.0497
    assert reproduction_report.path_interval([0.80, 0.82, 0.84]) == pytest.approx(
        (0.82 - 0.049683, 0.82 + 0.049683), abs=1e-6
    )
    assert reproduction_report.interval_verdict([0.80, 0.82, 0.84], 0.81) == (
        "undetermined (3 paths)",
        "95% t-interval [0.77, 0.87] over 3 paths",
    )
    assert reproduction_report.interval_verdict([0.90, 0.91, 0.92], 0.81)[0] == "holds"
    assert reproduction_report.interval_verdict([0.50, 0.51, 0.52], 0.81)[0] == "differs"
    assert reproduction_report.interval_verdict([0.95], 0.81) == (
        "undetermined (1 paths)",
        "1 path(s), no interval",
    )
    # a detection window [0.15, 0.35]: inside, outside above, straddling the edge
    assert reproduction_report.interval_verdict([0.18, 0.18, 0.19], 0.15, 0.35)[0] == "holds"
    assert reproduction_report.interval_verdict([0.60, 0.61, 0.62], 0.15, 0.35)[0] == "differs"
    assert reproduction_report.interval_verdict([0.30, 0.34, 0.38], 0.15, 0.35)[0] == (
        "undetermined (3 paths)"
    )
