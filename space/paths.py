"""Where tspace keeps its files by default, and where it finds the files it ships."""

from __future__ import annotations

import os
from pathlib import Path

# The package is installed editable: the shipped launch files, rules and ontology sit
# beside it, in the project's folder.
PROJECT = Path(__file__).resolve().parents[1]


def default_data_dir() -> Path:
    """Return `$XDG_DATA_HOME/tspace` (or `~/.local/share/tspace`)."""
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "tspace"


def shipped(relative: str | Path) -> Path:
    """Return `relative` in the current directory if it is there, else in the project's folder.

    For defaults only: a file the user names is read where they said.
    """
    path = Path(relative)
    return path if path.exists() else PROJECT / path
