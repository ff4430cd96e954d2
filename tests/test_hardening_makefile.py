"""The Makefile's torch install (issue 27): ``TORCH_INDEX_URL`` selects the wheel index.

Empty (the default): ``pip install torch==2.13.0`` from pip's default index, as before; set
(``make test TORCH_INDEX_URL=https://download.pytorch.org/whl/cpu``): the same pin with
``--index-url``, in the main install and in ``check-install``. ``make -n`` prints the recipes
without running them.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CPU = "https://download.pytorch.org/whl/cpu"

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="needs make")


def _torch_lines(tmp_path: Path, target: str, *settings: str) -> list[str]:
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
    return [ln for ln in out.splitlines() if re.search(r"pip install .* torch==", ln)]


@pytest.mark.parametrize("target", ["install", "check-install"])
def test_torch_comes_from_the_default_index_unless_set(tmp_path: Path, target: str) -> None:
    (line,) = _torch_lines(tmp_path, target)
    assert line.split()[-1] == "torch==2.13.0" and "--index-url" not in line
    (line,) = _torch_lines(tmp_path, target, f"TORCH_INDEX_URL={CPU}")
    assert line.split()[-3:] == ["torch==2.13.0", "--index-url", CPU]


def test_the_setting_is_documented_in_the_makefile() -> None:
    text = (ROOT / "Makefile").read_text()
    assert re.search(r"^## .*TORCH_INDEX_URL=https://download\.pytorch\.org/whl/cpu", text, re.M)
    assert re.search(r"^TORCH_INDEX_URL \?=\s*$", text, re.M)
