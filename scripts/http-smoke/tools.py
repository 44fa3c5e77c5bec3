"""Every tool of the catalogue with its README example, as one JSON object: ``{"list_topics": {}, ...}``.

The smokes (``.ci/run``'s Inspector part and ``run.sh``) list and call the tools from this, so neither keeps
a list of its own: the names come from ``catalogue.py`` in its order, each example is the first JSON object
in the "Example arguments" column of the tool's row in README.md's tools table. Exit 1 naming each tool of
the catalogue that has no row, or whose example is not a JSON object.

    uv run python scripts/http-smoke/tools.py            # the JSON object
    uv run python scripts/http-smoke/tools.py --names    # the names, one a line
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any

from rosbridge_mcp_server.catalogue import ALL_TOOL_NAMES

README = Path(__file__).resolve().parents[2] / "README.md"
#: A row of the tools table: ``| `name` | what it does | `{...}`, ... |``.
_ROW = re.compile(r"^\| `(?P<name>[a-z_]+)` \|.*\| `(?P<example>\{.*?\})`", re.MULTILINE)


def readme_examples(text: str) -> dict[str, Any]:
    """Each tool row's first example, read as JSON (rows whose example is not JSON are left out)."""
    examples: dict[str, Any] = {}
    for row in _ROW.finditer(text):
        try:
            examples.setdefault(row["name"], json.loads(row["example"]))
        except json.JSONDecodeError:
            continue
    return examples


def main(argv: list[str]) -> int:
    examples = readme_examples(README.read_text())
    missing = [name for name in ALL_TOOL_NAMES if not isinstance(examples.get(name), dict)]
    if missing:
        print(
            f"README.md's tools table has no row with a JSON example for {', '.join(missing)}.",
            file=sys.stderr,
        )
        return 1
    if "--names" in argv:
        print("\n".join(ALL_TOOL_NAMES))
    else:
        print(json.dumps({name: examples[name] for name in ALL_TOOL_NAMES}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
