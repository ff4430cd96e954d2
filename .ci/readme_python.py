"""Print the ```python blocks of a Markdown file (default README.md), one after another.

Used by ``make check-install`` to run the README's snippets against an installed wheel.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

BLOCK = re.compile(r"^```python\n(.*?)^```", re.DOTALL | re.MULTILINE)


def main() -> None:
    path = Path(sys.argv[1] if len(sys.argv) > 1 else "README.md")
    blocks = BLOCK.findall(path.read_text(encoding="utf-8"))
    if not blocks:
        sys.exit(f"{path}: no ```python block")
    print("\n".join(blocks))


if __name__ == "__main__":
    main()
