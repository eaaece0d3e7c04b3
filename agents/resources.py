"""Where the application finds the files it ships: launch files, rules, ontologies."""

from __future__ import annotations

from pathlib import Path

# The package is installed editable: the shipped files sit beside it, in the project's folder.
PROJECT = Path(__file__).resolve().parents[1]


def shipped(relative: str | Path) -> Path:
    """Return `relative` in the current directory if it is there, else in the project's folder.

    For defaults only: a file the user names is read where they said.
    """
    path = Path(relative)
    return path if path.exists() else PROJECT / path
