"""The reasoner's knowledge files: which rules and ontology it runs, and whether they changed."""

from __future__ import annotations

import logging
import os
import time
import warnings
from pathlib import Path

from agents.resources import data_file
from space.reasoning import Engine, UnsupportedAxiom, engine_from_files

log = logging.getLogger("tspace.reasoner")
RELOAD_PERIOD = 1.0  # seconds between looks at the rules files


class Knowledge:
    """The rules and ontology files (the shipped ones by default), watched for changes.

    Args:
        rules: rules files given on the command line, or None for the shipped ones.
        ontology: ontology files given, or None for the shipped one.
    """

    def __init__(self, rules: list[Path] | None, ontology: list[Path] | None) -> None:
        self.rules = rules or [data_file("rules/selfconfig.rules")]
        self.ontology = ontology or [data_file("ontology/selfconfig.ttl")]
        self._mtimes: dict[Path, float] = {}
        self._checked = 0.0

    def build(self) -> Engine:
        """Return an engine for the files as they are now, remembering their mtimes.

        Every rule form runs: forward rules in one engine, backward rules and rules
        nested in heads in a second layer over it, as Jena's hybrid mode (`build_engine`).

        Raises:
            RuleError: a rules file is invalid (the message has its line and column).
        """
        self._mtimes = self._stat()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UnsupportedAxiom)
            engine = engine_from_files(rules=self.rules, ontology=self.ontology)
        for w in caught:
            if issubclass(w.category, UnsupportedAxiom):
                log.warning("ontology: %s", w.message)
            else:
                warnings.showwarning(w.message, w.category, w.filename, w.lineno)
        return engine

    def changed(self) -> bool:
        """Return True if a rules file changed since `build` (looked at once a second)."""
        if time.monotonic() - self._checked < RELOAD_PERIOD:
            return False
        self._checked = time.monotonic()
        return self._stat() != self._mtimes

    def _stat(self) -> dict[Path, float]:
        """Return the mtimes of the rules files and of the rules files beside them (includes)."""
        paths: set[Path] = set()
        for path in self.rules:
            paths.add(path)
            paths.update(path.parent.glob("*.rules"))
        return {p: _mtime(p) for p in paths}


def _mtime(path: Path) -> float:
    try:
        return os.stat(path).st_mtime
    except OSError:
        return -1.0
