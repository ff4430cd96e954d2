"""Flight-to-flight damage scatter: scaled window vs whole flights vs closed form.

Logic in experiments.damage_scatter. Example (the docs/physics.md table, ~8 min):

    python scripts/damage_scatter.py --flights 40 --windows 60 --out results/damage_scatter.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from scas_env.cli_args import add_params_arg, check_out_file, load_params
from scas_env.utils.atomic_file import write_text_atomic


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", type=int, default=40, help="whole flights (>= 2)")
    parser.add_argument("--windows", type=int, default=60, help="windows per regime (>= 2)")
    parser.add_argument("--out", type=Path, required=True, help="output JSON")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    add_params_arg(parser)
    args = parser.parse_args(argv)
    for name in ("flights", "windows"):
        if getattr(args, name) < 2:
            parser.error(f"--{name} {getattr(args, name)} must be >= 2")
    check_out_file(parser, args.out, args.overwrite)
    params = load_params(parser, args)

    from experiments.damage_scatter import damage_scatter

    result = damage_scatter(params, n_flights=args.flights, n_windows=args.windows)
    text = json.dumps(result, indent=1)
    write_text_atomic(args.out, text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
