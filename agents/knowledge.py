"""The reasoner's knowledge files: which rules and ontology it runs, and whether they changed.

They are written into a space that lacks them (`Knowledge.seed`), so that other
agents and the HMI read the same ontology the reasoner runs.
"""

from __future__ import annotations

import logging
import os
import time
import warnings
from pathlib import Path

from rdflib import OWL, RDF, URIRef
from rdflib.term import Node

from agents.resources import data_file
from agents.vocabulary import AC
from space import TripleSpace
from space.reasoning import Engine, UnsupportedAxiom, engine_from_files, read_graph

log = logging.getLogger("tspace.reasoner")
RELOAD_PERIOD = 1.0  # seconds between looks at the rules files
ONTOLOGY_IRI = URIRef("https://w3id.org/tspace/selfconfig")


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

    def seed(
        self,
        ts: TripleSpace,
        robot: Node,
        robot_file: Path | None,
        timeout: float,
        agent_log: logging.Logger,
    ) -> None:
        """Write the ontology, and `robot_file` if its robot is not there, into the space."""
        if not len(ts.query((ONTOLOGY_IRI, RDF.type, OWL.Ontology))):
            ts.write(read_graph(self.ontology), timeout=timeout)
            agent_log.info("wrote the ontology into the space")
        if robot_file and not len(ts.query((robot, RDF.type, AC.Robot))):
            ts.write(read_graph([robot_file]), timeout=timeout)
            agent_log.info("wrote %s into the space", robot_file)

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
