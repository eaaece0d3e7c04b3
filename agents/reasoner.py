"""The reasoner: the space's rules engine, answering each changeset with its conclusions.

It holds the ontology and the rules (`space.reasoning.RuleEngine`), applies
every changeset other agents write, and writes back one changeset naming its
cause: what production rules changed (asserted) and what is entailed
(inferred graph), plus a record of each rule firing (`agents.firings`). Its
own changesets are ignored. A changed rules file is reloaded without a
restart; a broken one is logged with its line and column and the rules in
force stay. On start it writes the ontology (and `--robot-file`) into the
space when the space does not have them yet.

One reasoner serves a whole fleet. With `--per-robot`, one per robot instead
(a robot's reasoner can run on the robot): each applies every change, and
`agents.ownership` says which one writes the answer.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
import warnings
from collections import deque
from pathlib import Path

import zenoh
from rdflib import OWL, RDF, URIRef
from rdflib.term import Node

from agents.base import Agent, local_name, run_agent
from agents.conflicts import ConflictRecords
from agents.firings import FIRING_PREFIX, FiringLog, is_record
from agents.ownership import PREFIX, Roster, concerned_robot
from agents.view import AC
from space import Change, SpaceError, Subscription
from space.heap import refreeze
from space.reasoning import (
    Delta,
    Firing,
    Origin,
    RuleEngine,
    RuleError,
    UnsupportedAxiom,
    read_graph,
)
from space.request import Pending
from space.terms import Triple, triple_to_nt

REPO = Path(__file__).resolve().parents[1]
ONTOLOGY_IRI = URIRef("https://w3id.org/tspace/selfconfig")
RELOAD_PERIOD = 1.0
IN_FLIGHT = 64  # answers sent, not yet acknowledged, at most


class Reasoner(Agent):
    """Apply the self-configuration rules to every change of the space."""

    kind = "reasoner"
    per_robot = False
    keeps_view = False  # it decides from its engine, never from a view

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
        self.conflicts = ConflictRecords()
        self.roster = Roster(self.name) if args.per_robot else None
        self._others: zenoh.Subscriber | None = None
        self._joined: zenoh.LivelinessToken | None = None
        self._mtimes: dict[Path, float] = {}
        self._unacked: deque[tuple[str | None, Pending]] = deque()
        self._checked = 0.0
        self._loaded_seq = 0

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
            help="one reasoner per robot: answer for --robot (see agents.ownership)",
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

        Changes arriving meanwhile wait in the queue; those the loaded state
        holds already (by sequence number) are skipped after the load.
        """
        assert self.ts is not None
        if self.roster is not None and self._others is None:
            # Declared first: the reasoners present now are known once the engine is built.
            self._others = self.roster.watch(self.ts.session, self.ts.space)
        engine = self._build()
        # Its own answers and every firing record are left out before parsing: it ignores them.
        subscription = self.ts.subscribe(
            None,
            self._inbox.put,
            timeout=self.args.timeout,
            skip_own=True,
            skip_subjects=FIRING_PREFIX,
        )
        try:
            self._seed()
            asserted, inferred, seq = self.ts.graphs(timeout=self.args.timeout)
        except BaseException:
            self.ts.unsubscribe(subscription)  # setup() may retry: no second delivery
            raise
        if self.roster is not None and self._joined is None:
            # Subscribed, read, then joined: the changes after what it read are its own.
            self._joined = self.roster.join(self.ts.session, self.ts.space, seq)
        self.firings.restore(asserted)
        # In a canonical order: engines that load the same state fire the same way.
        state = sorted((t for t in asserted if not is_record(t)), key=triple_to_nt)
        delta = engine.load(state)
        self.engine, self._loaded_seq = engine, seq
        self.started = True
        self.log.info("loaded %d rules over %d asserted triples", len(engine.rules), len(asserted))
        if self.roster is None or self.roster.answers(None):
            self._write(delta, None, inferred_before=set(inferred))
        else:
            self.log.info("another per-robot reasoner leads: it concludes the load")
        return subscription

    def shutdown(self) -> None:
        """Withdraw from the per-robot reasoners, then leave the space."""
        try:
            self._settle()
            if self._joined is not None:
                self._joined.undeclare()
            if self._others is not None:
                self._others.undeclare()
        finally:
            self._joined, self._others = None, None
            super().shutdown()

    def _build(self) -> RuleEngine:
        """Return an engine for the rules and ontology files, remembering their mtimes.

        Raises:
            RuleError: a rules file is invalid (the message has its line and column).
        """
        self._mtimes = self._stat()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UnsupportedAxiom)
            engine = RuleEngine.from_files(rules=self.rules_files, ontology=self.ontology_files)
        for w in caught:
            if issubclass(w.category, UnsupportedAxiom):
                self.log.warning("ontology: %s", w.message)
            else:
                warnings.showwarning(w.message, w.category, w.filename, w.lineno)
        return engine

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
        """Apply another agent's changeset (firing records left out) and answer it."""
        if self.engine is None or change.seq <= self._loaded_seq:
            return  # in the state loaded
        added, removed = list(change.added), list(change.removed)
        removed += self._replaced(added, removed)
        if not added and not removed:
            return
        delta = self.engine.apply(added=added, removed=removed)
        if self.roster is not None:
            if change.agent.startswith(PREFIX):
                return  # another reasoner's answer: this engine concluded the same
            robot = concerned_robot(self.engine, [*added, *removed])
            if not self.roster.answers(robot, change.seq):
                return  # another reasoner answers, having drawn the same conclusions
        self._write(delta, change.id, wait=False)

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

    def _write(
        self,
        delta: Delta,
        cause: str | None,
        *,
        inferred_before: set[Triple] | None = None,
        wait: bool = True,
    ) -> None:
        """Write a delta (and its firing records) to the space as one changeset.

        Without `wait`, the store's acknowledgement is read later (`_settle`):
        changes waiting in the queue (a backlog after a cut) are answered without
        a round trip to the store each, in order; the run loop's tick, after the
        queue is empty, reads them.
        """
        assert self.ts is not None and self.engine is not None
        inferred_added, inferred_removed = list(delta.inferred_added), list(delta.inferred_removed)
        new_conflicts, gone_conflicts, conflicts = self.conflicts.update(self.engine.conflicts())
        for conflict in conflicts:
            self.log.warning("conflict (cause %s): %s", cause, conflict)
        if inferred_before is None:
            inferred_added += new_conflicts
            inferred_removed += gone_conflicts
        else:
            now = set(self.engine.triples(Origin.INFERRED)) | self.conflicts.triples()
            inferred_added, inferred_removed = (
                list(now - inferred_before),
                list(inferred_before - now),
            )
        added, removed = list(delta.asserted_added), list(delta.asserted_removed)
        robots: dict[Node, bool] = {}
        for firing in delta.firings:
            new, old = self.firings.record(firing.rule, cause, self._robot_of(firing, robots))
            added += new
            removed += old
        if delta.firings:
            # One line per answer: 200 firings logged one by one took milliseconds.
            rules = dict.fromkeys(firing.rule for firing in delta.firings)
            self.log.info("fired %d rule(s) (cause %s): %s", len(rules), cause, ", ".join(rules))
        if not (added or removed or inferred_added or inferred_removed):
            return
        cs = self.ts.changeset(
            added,
            removed,
            inferred_added=inferred_added,
            inferred_removed=inferred_removed,
            cause=cause,
        )
        if wait:
            self.ts.send(cs, timeout=self.args.timeout)
            return
        self._unacked.append((cause, self.ts.send_later(cs, timeout=self.args.timeout)))
        if len(self._unacked) > IN_FLIGHT:
            self._settle(len(self._unacked) - IN_FLIGHT)

    def _settle(self, count: int | None = None) -> None:
        """Read the acknowledgements of `count` answers in flight (all by default), oldest first.

        An answer the store did not acknowledge is logged, as a failed change is.
        """
        while self._unacked and (count is None or count > 0):
            cause, pending = self._unacked.popleft()
            try:
                pending.result()
            except SpaceError as exc:
                self.log.warning("answer to change %s: %s", cause, exc)
            if count is not None:
                count -= 1

    def _robot_of(self, firing: Firing, robots: dict[Node, bool]) -> Node:
        """Return the robot a firing concerned: the first robot among its premises, else `--robot`.

        `robots` remembers which subjects are robots for one answer: its
        firings share their premises' subjects, so the engine is asked once each.
        """
        assert self.engine is not None
        for s, _p, _o in firing.triggers:
            is_robot = robots.get(s)
            if is_robot is None:
                is_robot = robots[s] = (s, RDF.type, AC.Robot) in self.engine
            if is_robot:
                return s
        return self.robot

    # Rules reload

    def tick(self) -> None:
        """Read the answers' acknowledgements; reload the rules when a rules file changed.

        The rules files are checked every second.
        """
        self._settle()
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
            inferred_before = set(self.engine.triples(Origin.INFERRED)) | self.conflicts.triples()
            delta = engine.load(sorted(self.engine.triples(Origin.ASSERTED), key=triple_to_nt))
        except RuleError as exc:
            self.log.error("rules not reloaded, the previous rules stay in force: %s", exc)
            return
        self.engine = engine
        refreeze()  # the old engine is garbage now, out of the frozen generation
        self.log.info("rules reloaded: %d rules", len(engine.rules))
        if self.roster is None or self.roster.answers(None):
            self._write(delta, None, inferred_before=inferred_before)


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
