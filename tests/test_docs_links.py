"""Every relative link of the README, CHANGELOG and docs/*.md resolves: the file exists and,
for ``#anchor``, the target page has a heading with that GitHub anchor (lower case,
punctuation other than ``-`` and ``_`` dropped, spaces to ``-``, repeats numbered ``-1``...)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"```.*?```", re.S)


def anchors(page: Path) -> set[str]:
    """GitHub's anchors of a Markdown page's headings."""
    seen: dict[str, int] = {}
    out: set[str] = set()
    for line in FENCE.sub("", page.read_text(encoding="utf-8")).splitlines():
        m = re.match(r"#{1,6}\s+(.*)", line)
        if not m:
            continue
        text = re.sub(r"[`*]", "", m.group(1)).strip().lower()
        slug = re.sub(r"[^\w\- ]", "", text).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.add(slug if n == 0 else f"{slug}-{n}")
    return out


def links(page: Path) -> list[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    text = re.sub(r"`[^`\n]*`", "", text)  # code spans hold no links
    return [a or b for a, b in LINK.findall(text)]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_relative_links_resolve(page: Path) -> None:
    broken = []
    for target in links(page):
        if re.match(r"[a-z]+:", target):
            continue  # http(s), mailto
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists() or (anchor and dest.suffix == ".md" and anchor not in anchors(dest)):
            broken.append(target)
    assert not broken, f"{page.name}: broken links {broken}"


def test_the_checker_finds_a_broken_anchor_and_file(tmp_path: Path) -> None:
    """GitHub's slugs for two headings (backticks, slash, colon, a repeat), and a link to a
    missing heading or file is reported."""
    page = tmp_path / "p.md"
    page.write_text(
        "# Decision epochs: `scas_env/ScasMaintenanceEpochs-v2`\n## Held-out comparison\n"
        "## Held-out comparison\n```\n# not a heading\n```\n"
        "[a](#held-out-comparison-1) [b](#nope) [c](q.md#x) ![d](p.md)\n"
    )
    assert anchors(page) == {
        "decision-epochs-scas_envscasmaintenanceepochs-v2",
        "held-out-comparison",
        "held-out-comparison-1",
    }
    assert links(page) == ["#held-out-comparison-1", "#nope", "q.md#x", "p.md"]
    with pytest.raises(AssertionError, match=r"\['#nope', 'q.md#x'\]"):
        test_relative_links_resolve(page)
