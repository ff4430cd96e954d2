"""One table of reproduction verdicts with a column per sensing preset.

Input: the ``report.json`` of one reproduction per preset
(:func:`experiments.paper.reproduction_report.write_report`, e.g. the default parameters and
``--params`` of :func:`scas_env.actuator.presets.preset_params` saved to a file). Output: a
markdown table, one row per claim of [DJS20], per preset its "ours" value (the seal's
worn-depth fraction in brackets where reported) and its verdict.

    python -m experiments.paper.reproduction_presets \
        realistic=results/repro_default/report.json paper=results/repro_paper/report.json
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["main", "preset_table", "read_reports"]


def read_reports(paths: dict[str, str | Path]) -> dict[str, dict[str, Any]]:
    """``{preset: report.json content}``; every file must be a JSON object with a
    ``verdicts`` list, and all must hold the same claims in order (``ValueError`` naming the
    file otherwise)."""
    reports = {}
    for name, p in paths.items():
        try:
            report = json.loads(Path(p).read_text())
        except json.JSONDecodeError as err:
            raise ValueError(f"{name}={p} is not valid JSON ({err})") from None
        verdicts = report.get("verdicts") if isinstance(report, dict) else None
        if not isinstance(verdicts, list) or not all(
            isinstance(r, dict) and "claim" in r for r in verdicts
        ):
            raise ValueError(
                f"{name}={p} holds no 'verdicts' list of claims; expected the report.json "
                "of python -m experiments.paper.reproduce"
            )
        reports[name] = report
    claims = [[r["claim"] for r in rep["verdicts"]] for rep in reports.values()]
    if any(c != claims[0] for c in claims[1:]):
        raise ValueError(f"reports {list(paths)} hold different claims: compare like with like")
    return reports


def preset_table(reports: dict[str, dict[str, Any]]) -> str:
    """Markdown table: claim, paper, then ``ours`` and verdict per preset (module doc)."""
    names = list(reports)
    head = "| result | paper | " + " | ".join(f"{n} | {n}: verdict" for n in names) + " |"
    lines = [head, "|---|---|" + "---|---|" * len(names)]
    first = reports[names[0]]["verdicts"]
    for k, row in enumerate(first):
        cells = []
        for n in names:
            r = reports[n]["verdicts"][k]
            depth = r.get("ours_worn_depth", "")
            cells += [f"{r['ours']}" + (f" [worn depth: {depth}]" if depth else ""), r["verdict"]]
        lines.append(f"| {row['claim']} | {row['paper']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Print the table of the given ``NAME=path/to/report.json`` reports (markdown)."""
    from scas_env.cli_args import make_parser

    parser = make_parser("python -m experiments.paper.reproduction_presets", __doc__)
    parser.add_argument("reports", nargs="+", help="NAME=path/to/report.json, one per preset")
    args = parser.parse_args(argv)
    paths: dict[str, str] = {}
    for item in args.reports:
        name, sep, path = item.partition("=")
        if not sep or not name or not path:
            parser.error(f"{item!r} must read NAME=path/to/report.json")
        if name in paths:
            parser.error(
                f"preset name {name!r} is given twice ({paths[name]} and {path}); "
                "each column needs its own NAME"
            )
        paths[name] = path
    try:
        print(preset_table(read_reports(paths)), end="")
    except (OSError, ValueError, KeyError) as exc:
        parser.error(str(exc))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
