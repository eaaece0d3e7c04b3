"""The reasoner: the space's rules engine, answering each changeset with its conclusions.

It holds the ontology and the rules (`space.reasoning.RuleEngine`), applies
every changeset other agents write, and writes back one changeset naming its
cause: what production rules changed (asserted) and what is entailed
(inferred graph), plus a record of each rule firing (`agents.firings`). Its
own changesets are ignored. A changed rules file is reloaded without a
restart; a broken one is logged with its line and column and the rules in
force stay. On start it writes the ontology (and `--robot-file`) into the
space when the space does not have them yet.

One reasoner serves a whole fleet. With `--per-robot`, one per robot instead:
each applies every change but writes only what `agents.ownership` gives its
robot, so a robot's reasoner can run on the robot.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

from rdflib import OWL, RDF, URIRef
from rdflib.term import Node

from agents.base import Agent, local_name, run_agent
from agents.firings import FIRING_PREFIX, FiringLog, is_record
from agents.ownership import Answer, concerned_robot, firing_robot
from agents.view import AC
from space import Change, Subscription
from space.reasoning import Delta, Firing, Origin, RuleEngine, RuleError, read_graph
from space.terms import Triple

REPO = Path(__file__).resolve().parents[1]
ONTOLOGY_IRI = URIRef("https://w3id.org/tspace/selfconfig")
RELOAD_PERIOD = 1.0


class Reasoner(Agent):
    """Apply the self-configuration rules to every change of the space."""

    kind = "reasoner"
    per_robot = False

    def __init__(self, args: argparse.Namespace) -> None:
        super().__init__(args)
        prefix = FIRING_PREFIX
        if args.per_robot:
            # Several reasoners write into one space: names and records of their own.
            self.name = args.name or f"{self.kind}.{local_name(self.robot)}"
            self.log = logging.getLogger(self.name)
            prefix += f"{local_name(self.robot)}_"
        self.engine: RuleEngine | None = None
        self.firings = FiringLog(args.keep_firings, prefix)
        self._mtimes: dict[Path, float] = {}
        self._checked = 0.0

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add the knowledge options."""
        parser.add_argument(
            "--rules",
            action="append",
            type=Path,
            metavar="FILE",
            help="Jena rules file (repeatable; default rules/selfconfig.rules)",
        )
        parser.add_argument(
            "--ontology",
            action="append",
            type=Path,
            metavar="FILE",
            help="ontology file (repeatable; default ontology/selfconfig.ttl)",
        )
        parser.add_argument(
            "--robot-file",
            type=Path,
            metavar="FILE",
            help="a robot description written into the space if its robot is not there",
        )
        parser.add_argument(
            "--keep-firings",
            type=int,
            default=100,
            metavar="N",
            help="firing records kept in the space (default 100)",
        )
        parser.add_argument(
            "--per-robot",
            action="store_true",
            help="answer for --robot only, beside one such reasoner per robot (agents.ownership)",
        )

    @property
    def rules_files(self) -> list[Path]:
        """Return the rules files given, or the default one."""
        return self.args.rules or [REPO / "rules" / "selfconfig.rules"]

    @property
    def ontology_files(self) -> list[Path]:
        """Return the ontology files given, or the default one."""
        return self.args.ontology or [REPO / "ontology" / "selfconfig.ttl"]

    # Start

    def subscribe(self) -> Subscription:
        """Subscribe, then load the asserted graph into a fresh engine and reconcile.

        Changes arriving meanwhile wait in the queue and are applied after the
        load; applying a change the loaded state already reflects changes nothing.
        """
        assert self.ts is not None
        engine = self._build()
        subscription = self.ts.subscribe(None, self._inbox.put, timeout=self.args.timeout)
        try:
            self._seed()
            asserted = set(self.ts.query(None, graph="asserted", timeout=self.args.timeout))
            inferred = set(self.ts.query(None, graph="inferred", timeout=self.args.timeout))
        except BaseException:
            self.ts.unsubscribe(subscription)  # setup() may retry: no second delivery
            raise
        self.firings.restore(asserted)
        delta = engine.load(t for t in asserted if not is_record(t))
        self.engine = engine
        self.started = True
        self.log.info("loaded %d rules over %d asserted triples", len(engine.rules), len(asserted))
        self._write(self._reconciled(delta, inferred), None)
        return subscription

    def _build(self) -> RuleEngine:
        """Return an engine for the rules and ontology files, remembering their mtimes.

        Raises:
            RuleError: a rules file is invalid (the message has its line and column).
        """
        self._mtimes = self._stat()
        return RuleEngine.from_files(rules=self.rules_files, ontology=self.ontology_files)

    def _seed(self) -> None:
        """Write the ontology and the robot file into the space if it lacks them."""
        assert self.ts is not None
        if not len(self.ts.query((ONTOLOGY_IRI, RDF.type, OWL.Ontology))):
            self.ts.write(read_graph(self.ontology_files), timeout=self.args.timeout)
            self.log.info("wrote the ontology into the space")
        robot_file = self.args.robot_file
        if robot_file and not len(self.ts.query((self.robot, RDF.type, AC.Robot))):
            self.ts.write(read_graph([robot_file]), timeout=self.args.timeout)
            self.log.info("wrote %s into the space", robot_file)

    # Changes

    def on_change(self, change: Change) -> None:
        """Apply another agent's changeset and answer it with the conclusions."""
        if change.agent == self.name or self.engine is None:
            return
        added = [t for t in change.added if not is_record(t)]
        removed = [t for t in change.removed if not is_record(t)]
        removed += self._replaced(added, removed)
        if not added and not removed:
            return
        answer = Answer.of(self.engine.apply(added=added, removed=removed))
        if self.args.per_robot:
            robot = concerned_robot(self.engine, [*added, *removed])
            if robot is None:
                answer = self._shared(answer)
            elif robot != self.robot:
                return  # that robot's reasoner answers, having drawn the same conclusions
        self._write(answer, change.id)

    def _shared(self, answer: Answer) -> Answer:
        """Return the part of an answer to a shared change this reasoner writes."""
        assert self.engine is not None
        return answer.share(self.engine, self.robot) if self.args.per_robot else answer

    def _replaced(self, added: list[Triple], removed: list[Triple]) -> list[Triple]:
        """Return the old values of functional properties that `added` replaces.

        The store replaces them too; doing it here keeps the engine's state the
        store's even when a writer did not say what it replaced.
        """
        engine, out = self.engine, []
        assert engine is not None
        for s, p, o in added:
            if (p, RDF.type, OWL.FunctionalProperty) in engine:
                out += [t for t in engine.match(s, p) if t[2] != o and t not in removed]
        return out

    def _reconciled(self, delta: Delta, inferred_before: set[Triple]) -> Answer:
        """Return the answer to a (re)load of the engine.

        Its inferred changes turn what the space's inferred graph held
        (`inferred_before`) into what the engine infers now.
        """
        assert self.engine is not None
        now = set(self.engine.triples(Origin.INFERRED))
        answer = replace(
            Answer.of(delta),
            inferred_added=tuple(now - inferred_before),
            inferred_removed=tuple(inferred_before - now),
        )
        return self._shared(answer)

    def _write(self, answer: Answer, cause: str | None) -> None:
        """Write an answer (and its firing records) to the space as one changeset."""
        assert self.ts is not None and self.engine is not None
        inferred_added, inferred_removed = answer.inferred_added, answer.inferred_removed
        added, removed = list(answer.added), list(answer.removed)
        for firing in answer.firings:
            self.log.info("fired %s (cause %s)", firing.rule, cause)
            new, old = self.firings.record(firing.rule, cause, self._robot_of(firing))
            added += new
            removed += old
        if not (added or removed or inferred_added or inferred_removed):
            return
        self.ts.apply(
            added,
            removed,
            inferred_added=inferred_added,
            inferred_removed=inferred_removed,
            cause=cause,
            timeout=self.args.timeout,
        )

    def _robot_of(self, firing: Firing) -> Node:
        """Return the robot a firing concerned: a robot among its premises, else `--robot`."""
        assert self.engine is not None
        return firing_robot(self.engine, firing) or self.robot

    # Rules reload

    def tick(self) -> None:
        """Reload the rules when a rules file changed (checked every second)."""
        if time.monotonic() - self._checked < RELOAD_PERIOD:
            return
        self._checked = time.monotonic()
        if self._stat() != self._mtimes:
            self._reload()

    def _stat(self) -> dict[Path, float]:
        """Return the mtimes of the rules files and of the rules files beside them (includes)."""
        paths: set[Path] = set()
        for path in self.rules_files:
            paths.add(path)
            paths.update(path.parent.glob("*.rules"))
        return {p: _mtime(p) for p in paths}

    def _reload(self) -> None:
        """Swap in an engine for the changed rules over the same asserted state."""
        assert self.engine is not None
        try:
            engine = self._build()
            inferred_before = set(self.engine.triples(Origin.INFERRED))
            delta = engine.load(self.engine.triples(Origin.ASSERTED))
        except RuleError as exc:
            self.log.error("rules not reloaded, the previous rules stay in force: %s", exc)
            return
        self.engine = engine
        self.log.info("rules reloaded: %d rules", len(engine.rules))
        self._write(self._reconciled(delta, inferred_before), None)


def _mtime(path: Path) -> float:
    try:
        return os.stat(path).st_mtime
    except OSError:
        return -1.0


def main(argv: list[str] | None = None) -> int:
    """Run the reasoner (see `--help`)."""
    return run_agent(Reasoner, argv)


if __name__ == "__main__":
    sys.exit(main())
