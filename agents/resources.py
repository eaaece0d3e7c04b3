"""Where the application finds the files it ships: launch files, rules, ontologies.

They are package data of `agents.data` (the project's `deploy/`, `rules/` and
`ontology/`, linked there), read through `importlib.resources` so that an
installed wheel finds them as a checkout does. The wheel installs them as plain
files, which rule files need: `@include` and launch files name their neighbours.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from space import InputError


def data_file(relative: str | Path) -> Path:
    """Return a shipped file or folder, e.g. `rules/selfconfig.rules`.

    Raises:
        InputError: the installation lacks it (a broken or zipped install).
    """
    path = Path(str(files("agents.data").joinpath(*Path(relative).parts)))
    if not path.exists():
        raise InputError(f"the shipped file {relative} is missing from {path.parent}")
    return path


def shipped(relative: str | Path) -> Path:
    """Return `relative` in the current directory if it is there, else the shipped one.

    For defaults only: a file the user names is read where they said.
    """
    path = Path(relative)
    return path if path.exists() else data_file(relative)
