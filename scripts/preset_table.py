"""Reproduction verdicts with a column per sensing preset (markdown to stdout).

Logic in scas_env.studies.reproduction_presets. Example:

    python scripts/preset_table.py realistic=results/repro_default/report.json \
        paper=results/repro_paper/report.json
"""

from __future__ import annotations

import argparse

from scas_env.studies.reproduction_presets import preset_table, read_reports


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("reports", nargs="+", help="NAME=path/to/report.json, one per preset")
    args = parser.parse_args(argv)
    paths = {}
    for item in args.reports:
        name, sep, path = item.partition("=")
        if not sep or not name or not path:
            parser.error(f"{item!r} must read NAME=path/to/report.json")
        paths[name] = path
    try:
        print(preset_table(read_reports(paths)), end="")
    except (OSError, ValueError, KeyError) as exc:
        parser.error(str(exc))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
