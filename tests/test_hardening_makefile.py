"""The Makefile's torch install (``install_torch``): where pip gets torch 2.13.0.

``TORCH_INDEX_URL`` set: that index. Unset: a wheel pip finds without any index (a local
wheel), else PyTorch's CPU index, never the default index's CUDA build. ``make -n`` prints
the recipe's shell command; the tests run that command against a fake ``pip`` that records
its arguments and answers the dry run as a machine with or without a local wheel would.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CPU = "https://download.pytorch.org/whl/cpu"
MIRROR = "https://example.org/torch-wheels"

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="needs make")


def _install_line(tmp_path: Path, target: str, *settings: str) -> str:
    env = {k: v for k, v in os.environ.items() if k != "TORCH_INDEX_URL"}
    out = subprocess.run(
        [
            "make",
            "-n",
            "-C",
            str(ROOT),
            target,
            f"VENV={tmp_path / 'venv'}",
            f"CHECK_DIR={tmp_path / 'check'}",
            *settings,
        ],
        capture_output=True,
        text=True,
        check=True,
        env=env,
    ).stdout
    (line,) = [ln for ln in out.splitlines() if "torch==2.13.0" in ln]
    return line


def _pip_calls(tmp_path: Path, target: str, local_wheel: bool, *settings: str) -> list[str]:
    """Run the recipe's torch command with a fake pip; the pip calls it made, in order."""
    log = tmp_path / "pip.log"
    dry_run_exit = 0 if local_wheel else 1
    body = f'echo "$*" >> {log}\ncase "$*" in *--dry-run*) exit {dry_run_exit};; esac\n'
    line = _install_line(tmp_path, target, *settings)
    # `install` calls `<venv>/bin/python -m pip ...`, `check-install` `<venv>/bin/pip ...`
    fakes = {"venv/bin/python": "shift 2\n" + body, "check/venv/bin/pip": body}
    for rel, script in fakes.items():
        path = tmp_path / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("#!/bin/sh\n" + script)
        path.chmod(path.stat().st_mode | stat.S_IEXEC)
    subprocess.run(["sh", "-c", line], check=True)
    return log.read_text().splitlines()


@pytest.mark.parametrize("target", ["install", "check-install"])
def test_without_a_setting_a_local_wheel_wins(tmp_path: Path, target: str) -> None:
    *probe, call = _pip_calls(tmp_path, target, local_wheel=True)
    assert len(probe) == 1 and "--dry-run --no-index" in probe[0]
    assert call.split()[-1] == "torch==2.13.0" and "--index-url" not in call


@pytest.mark.parametrize("target", ["install", "check-install"])
def test_without_a_local_wheel_the_cpu_index_is_used(tmp_path: Path, target: str) -> None:
    *_, call = _pip_calls(tmp_path, target, local_wheel=False)
    assert call.split()[-3:] == ["torch==2.13.0", "--index-url", CPU]


@pytest.mark.parametrize("target", ["install", "check-install"])
def test_the_setting_overrides_both(tmp_path: Path, target: str) -> None:
    calls = _pip_calls(tmp_path, target, True, f"TORCH_INDEX_URL={MIRROR}")
    assert calls == [f"install --disable-pip-version-check -q torch==2.13.0 --index-url {MIRROR}"]


def test_the_setting_is_documented_in_the_makefile() -> None:
    text = (ROOT / "Makefile").read_text()
    assert re.search(r"^## .*TORCH_INDEX_URL when set", text, re.M)
    assert re.search(r"^TORCH_INDEX_URL \?=\s*$", text, re.M)
