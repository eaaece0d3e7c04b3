"""Where tspace keeps its files by default."""

from __future__ import annotations

import os
from pathlib import Path


def default_data_dir() -> Path:
    """Return `$XDG_DATA_HOME/tspace` (or `~/.local/share/tspace`)."""
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "tspace"
