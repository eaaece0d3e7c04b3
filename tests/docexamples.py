"""Read the fenced examples of a Markdown file and run them against a running `tspace up`.

A fence's info string is its language, then, for a shell or Python example that is not meant
to run here, `no-run:` and why (```` ```sh no-run: three hosts ````). Every fence names its
language (`text` for output and diagrams), so no command hides in an unmarked block.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

RUNNABLE = ("sh", "python")
_FENCE = re.compile(r"^```([^\n]*)\n(.*?)^```[ \t]*$", re.S | re.M)
_NO_RUN = re.compile(r"\bno-run\b:?\s*(.*)")


@dataclass(frozen=True)
class Block:
    """One fenced block: where it starts, its language, why it does not run (if so), its code."""

    path: Path
    line: int
    language: str
    no_run: str | None
    code: str

    def __str__(self) -> str:
        return f"{self.path.name}:{self.line} ({self.language})"

    @property
    def runs(self) -> bool:
        return self.language in RUNNABLE and self.no_run is None


def fenced(path: Path) -> list[Block]:
    """Return the fenced blocks of a Markdown file, in order."""
    text = path.read_text()
    blocks = []
    for match in _FENCE.finditer(text):
        info = match.group(1).strip()
        language, _, rest = info.partition(" ")
        no_run = _NO_RUN.search(rest)
        line = text.count("\n", 0, match.start()) + 1
        reason = no_run.group(1).strip() if no_run else None
        blocks.append(Block(path, line, language, reason, match.group(2)))
    return blocks


def shell_prelude(python: str, endpoint: str) -> str:
    """Return bash that makes `tspace` and `python` run this checkout against `endpoint`.

    Commands that use a space get `--connect endpoint`; `watch` runs until a timeout (its
    success, as Ctrl-C is for a user); a `query` whose table has no row fails the example,
    since an example that finds nothing shows nothing.
    """
    return f"""
set -euo pipefail
tspace() {{
    case "$1" in
        watch) timeout 3 {python} -m space.cli "$@" --connect {endpoint} || [ $? = 124 ];;
        query)
            local out rows
            out=$({python} -m space.cli "$@" --connect {endpoint})
            printf '%s\\n' "$out"
            rows=$(printf '%s\\n' "$out" | grep -c . || true)
            if printf '%s\\n' "$out" | sed -n 2p | grep -qE '^[- ]+$'; then
                rows=$((rows - 2))  # a table's header and its rule
            fi
            if [ "$rows" -lt 1 ]; then
                echo "example found nothing: tspace $*" >&2
                return 1
            fi;;
        write|take|why) {python} -m space.cli "$@" --connect {endpoint};;
        *) {python} -m space.cli "$@";;
    esac
}}
python() {{ {python} "$@"; }}
"""
