"""The reasoner: the space's rules engine, answering each changeset with its conclusions.

It holds the ontology and the rules (`space.reasoning.build_engine`: every Jena rule
form, backward and nested rules in a second layer as Jena's hybrid mode), applies
every changeset other agents write, and writes back one changeset naming its
cause: what production rules changed (asserted) and what is entailed
(inferred graph), plus a record of each rule firing (`agents.firings`). Its
own changesets are ignored. Changes come in, and answers go out, as the wire has their
terms (N-Triples texts, `Engine.apply_texts`): a term is parsed once, when the engine
first meets it. A changed rules file is reloaded without a
restart; a broken one is logged with its line and column and the rules in
force stay. On start it writes the ontology (and `--robot-file`) into the
space when the space does not have them yet (`agents.knowledge`). It answers `why` on the space's
`@/why` queryable (`space.WhyService`; who wrote what: `agents.writers`).

One reasoner serves a whole fleet. With `--per-robot`, one per robot instead
(a robot's reasoner can run on the robot): each applies every change, and
`agents.ownership` says which one writes the answer.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable
from dataclasses import replace

import zenoh
from rdflib import OWL
from rdflib.term import Node

from agents.answers import Ledger, present_truth
from agents.base import Agent, run_agent
from agents.conflicts import ConflictRecords
from agents.firings import FIRING_PREFIX, FiringLog, without_records
from agents.in_flight import InFlight
from agents.knowledge import Knowledge
from agents.ownership import PREFIX, Roster, concerned_robot, firing_robot
from agents.reasoner_options import add_reasoner_arguments
from agents.vocabulary import RDF_TYPE, local_name
from agents.writers import Writers
from space import (
    Change,
    Changeset,
    Explanation,
    Subscription,
    Template,
    TextTriple,
    Triple,
    WhyService,
    freeze_startup,
    refreeze,
    replace_functional,
    text_of,
    to_nt,
    triple_from_nt,
    triple_to_nt,
)
from space.reasoning import (
    Delta,
    Engine,
    Explainer,
    Origin,
    RuleError,
    RuleLoopError,
)

# The texts of the terms `_replaced` asks about, as changes carry them.
_TYPE, _FUNCTIONAL = to_nt(RDF_TYPE), to_nt(OWL.FunctionalProperty)


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
        self.engine: Engine | None = None
        self.firings = FiringLog(args.keep_firings, prefix)
        self.conflicts = ConflictRecords()
        self.roster = Roster(self.name) if args.per_robot else None
        self._others: zenoh.Subscriber | None = None
        self._joined: zenoh.LivelinessToken | None = None
        self.knowledge = Knowledge(args.rules, args.ontology)
        self._in_flight = InFlight(args.timeout, self._stop, self.log)
        self._ledger = Ledger()
        self._diverged = False  # an answer was not taken, and no resync has succeeded since
        self._loaded_seq = 0
        self.writers = Writers(self._history)
        self.why = WhyService()
        self._explainer: Explainer | None = None

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """Add the knowledge options (`agents.reasoner_options`)."""
        add_reasoner_arguments(parser)

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
        engine = self.knowledge.build()
        # Its own answers are left out before parsing: it ignores them.
        subscription = self.ts.subscribe(
            None, self._receive, timeout=self.args.timeout, skip_own=True, texts=True
        )
        try:
            args = self.args
            self.knowledge.seed(self.ts, self.robot, args.robot_file, args.timeout, self.log)
            asserted, inferred, seq = self.ts.graphs(timeout=self.args.timeout)
        except BaseException:
            self.ts.unsubscribe(subscription)  # setup() may retry: no second delivery
            raise
        if self.roster is not None and self._joined is None:
            # Subscribed, read, then joined: the changes after what it read are its own.
            self._joined = self.roster.join(self.ts.session, self.ts.space, seq)
        self.firings.restore(asserted)
        self.started = True
        leads = self.roster is None or self.roster.answers(None)
        if not leads:
            self.log.info("another per-robot reasoner leads: it concludes the load")
        self._load(engine, asserted, inferred, seq, write=leads)
        return subscription

    def _load(
        self,
        engine: Engine,
        asserted: list[Triple],
        inferred: list[Triple],
        seq: int,
        *,
        write: bool,
    ) -> None:
        """Load the space's state (as of change `seq`) into `engine`, make it this reasoner's.

        With `write`, what loading concluded beyond the space is written into it.
        """
        # In a canonical order: engines that load the same state fire the same way.
        state = sorted(without_records(asserted), key=triple_to_nt)
        delta, loop = _applying(lambda: engine.load(state))
        if self.engine is None:
            # Frozen before its first answer, not after (`run_agent` freezes after setup): that
            # full collection (50-80 ms with a fleet of 200 robots) then held up the first
            # changes, which the writers send as soon as the load is answered.
            freeze_startup()
        self.engine, self._loaded_seq = engine, seq
        self._explainer = None
        self.writers.loaded(seq)
        self.why.open(self.ts.session, self.ts.space)
        self.log.info("loaded %d rules over %d asserted triples", len(engine.rules), len(asserted))
        if loop is not None:
            self.log.error("loading the space: %s; those firings undone", loop)
        if write:
            self._write(in_texts(delta), None, inferred_before=set(inferred), loop=loop)

    def _resync(self) -> None:
        """Rebuild the engine from the space, after an answer the space did not take.

        The engine applied that answer's production changes; the space did not.
        Reading the space back and writing what it lacks makes them one again.
        """
        assert self.ts is not None
        asserted, inferred, seq = self.ts.graphs(timeout=self.args.timeout)
        self._load(self.knowledge.build(), list(asserted), list(inferred), seq, write=True)
        self._diverged = False
        self.log.warning("resynchronised from the space at change %d", seq)

    def shutdown(self) -> None:
        """Withdraw from the per-robot reasoners, then leave the space."""
        try:
            self.why.close()
            self._settle()
            if self._joined is not None:
                self._joined.undeclare()
            if self._others is not None:
                self._others.undeclare()
        finally:
            self._joined, self._others = None, None
            super().shutdown()

    # Changes

    def on_change(self, change: Change) -> None:
        """Apply another agent's changeset (another reasoner's records left out), answer it.

        Its triples are N-Triples texts; one the engine cannot parse drops the change
        before anything is applied (`MalformedPayload`, logged by the caller).
        """
        if self.engine is None or change.seq <= self._loaded_seq:
            return  # in the state loaded
        from_reasoner = self.roster is not None and change.agent.startswith(PREFIX)
        if from_reasoner:
            self._ledger.answered(change.cause)
        engine = self.engine
        # In the engine's form of each term, as the texts it answers with and `why` looks
        # up (the store's differ for some literals); a text that does not parse stops here.
        added = engine.terms.canonical(without_records(change.added, texts=True))
        removed = engine.terms.canonical(without_records(change.removed, texts=True))
        removed += self._replaced(added, removed)
        self.writers.note(change, added, removed)
        if not added and not removed:
            return
        delta, loop = _applying(lambda: engine.apply_texts(added, removed))
        if loop is not None:
            self.log.error("change %s: %s; those firings undone, the change kept", change.id, loop)
        if self.roster is not None:
            if from_reasoner:
                return  # another reasoner's answer: this engine concluded the same
            robot = concerned_robot(self.engine, [triple_from_nt(t) for t in (*added, *removed)])
            if not self.roster.answers(robot, change.seq):
                # Another reasoner answers, having drawn the same conclusions; until its
                # answer is seen, this one can stand in for it if it dies.
                self._ledger.note(change.id, change.seq, robot, delta)
                return
        self._write(delta, change.id, wait=False, loop=loop)

    def _replaced(self, added: list[TextTriple], removed: list[TextTriple]) -> list[TextTriple]:
        """Return the old values of functional properties that `added` replaces (texts).

        The store replaces them too; doing it here keeps the engine's state the
        store's even when a writer did not say what it replaced.
        """
        engine = self.engine
        assert engine is not None
        functional: dict[str, bool] = {}  # by predicate: asked once per change

        def is_functional(p: str) -> bool:
            found = functional.get(p)
            if found is None:
                found = functional[p] = engine.holds_texts(p, _TYPE, _FUNCTIONAL)
            return found

        change = replace_functional(
            added,  # type: ignore[arg-type]
            is_functional,  # type: ignore[arg-type]
            lambda s, p: [t[2] for t in engine.match_texts(s, p)],  # type: ignore[arg-type]
        )
        return [t for t in change.replaced if t not in removed]

    def _write(
        self,
        delta: Delta,
        cause: str | None,
        *,
        inferred_before: set[Triple] | None = None,
        wait: bool = True,
        loop: RuleLoopError | None = None,
    ) -> None:
        """Write a delta in texts (and its firing records) to the space as one changeset.

        `inferred_before`: the inferred triples (rdflib terms) the space held before a
        load, to write the difference from the engine's. Without `wait`, the store's
        acknowledgement is read later (`agents.in_flight`): changes are answered without
        a round trip to the store each, in order; the run loop's ticks read the
        acknowledgements as they come in.
        """
        assert self.ts is not None and self.engine is not None
        inferred_added, inferred_removed = list(delta.inferred_added), list(delta.inferred_removed)
        new_conflicts, gone_conflicts, conflicts = self.conflicts.update(self.engine.conflicts())
        for conflict in conflicts:
            self.log.warning("conflict (cause %s): %s", cause, conflict)
        if inferred_before is None:
            inferred_added += map(text_of, new_conflicts)
            inferred_removed += map(text_of, gone_conflicts)
        else:
            now = set(self.engine.triples(Origin.INFERRED)) | self.conflicts.triples()
            inferred_added, inferred_removed = (
                list(map(text_of, now - inferred_before)),
                list(map(text_of, inferred_before - now)),
            )
        concluded = list(delta.asserted_added), list(delta.asserted_removed)
        added, removed = list(concluded[0]), list(concluded[1])
        robots: dict[Node, bool] = {}
        fired: dict[Node, list[str]] = {}  # robot -> the rules that fired for it, in order
        for firing in delta.firings:
            robot = firing_robot(self.engine, firing, robots, self.robot)
            fired.setdefault(robot, []).append(firing.rule)
        for robot, rules in fired.items():
            new, old = self.firings.record(rules, cause, robot)
            added += new
            removed += old
        if loop is not None:
            new, old = self.firings.loop(loop.rules, cause, self.robot)
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
        cs.texts = True
        self.writers.note(cs, *concluded)  # not the records: `why` is never asked about them
        if wait:
            self.ts.send(cs, timeout=self.args.timeout)
            return
        excess = self._in_flight.send(self.ts, cs)
        if excess:
            self._settle(excess)

    def _settle(self, count: int | None = None, *, wait: bool = True) -> None:
        """Read the acknowledgements of `count` answers in flight (all by default), oldest first
        (without `wait`, those already in).

        An answer the store did not take leaves the engine ahead of the space: once
        the answers in flight are read, the engine is rebuilt from the space (`_resync`).
        """
        assert self.ts is not None
        if self._in_flight.settle(self.ts, count, wait=wait):
            self._diverged = True
            self._resync()

    # Rules reload

    def tick(self) -> None:
        """Read the answers' acknowledgements already in; reload the rules when a rules file
        changed.

        Not waiting for the others: a tick follows every batch of changes, and
        waiting there for the store's round trip held the next changes back by as
        much (bench/fleet.py at 2,000 changesets/s). The rules files are checked
        every second. Answers another per-robot reasoner owed and can no longer
        give (it left) are written here.
        """
        self._settle(wait=False)
        self.why.answer_pending(self._explain)
        if self._diverged:
            self._resync()  # the store was away when it was first tried: again, every tick
        if self.roster is not None and self.engine is not None and len(self._ledger):
            for owed in self._ledger.take(self.roster.answers):
                self.log.warning("answering change %s for a reasoner that left", owed.id)
                self._write(present_truth(self.engine, [owed.delta]), owed.id, wait=False)
        if self.knowledge.changed():
            self._reload()

    def _reload(self) -> None:
        """Swap in an engine for the changed rules over the same asserted state."""
        assert self.engine is not None
        try:
            engine = self.knowledge.build()
            inferred_before = set(self.engine.triples(Origin.INFERRED)) | self.conflicts.triples()
            delta = engine.load(sorted(self.engine.triples(Origin.ASSERTED), key=triple_to_nt))
        except RuleError as exc:
            self.log.error("rules not reloaded, the previous rules stay in force: %s", exc)
            return
        self.engine, self._explainer = engine, None
        refreeze()  # the old engine is garbage now, out of the frozen generation
        self.log.info("rules reloaded: %d rules", len(engine.rules))
        if self.roster is None or self.roster.answers(None):
            self._write(in_texts(delta), None, inferred_before=inferred_before)

    # Why

    def _explain(self, template: Template, limit: int) -> tuple[list[Explanation], bool]:
        """Explain at most `limit` matching triples the engine holds, in N-Triples order."""
        assert self.engine is not None
        matches = sorted(
            self.engine.match(*template.pattern()),  # records never enter the engine
            key=triple_to_nt,
        )
        if self._explainer is None:
            self._explainer = Explainer(self.engine.why, self.engine.rules, self.writers.lookup)
        return self._explainer.explain(matches[:limit]), len(matches) > limit

    def _history(self, first: int, last: int) -> list[Changeset]:
        assert self.ts is not None
        return self.ts.history(first, last, timeout=self.args.timeout)[0]


def in_texts(delta: Delta) -> Delta:
    """Return a `Delta` of rdflib terms (a load's) with the triples an answer writes in texts."""
    return replace(
        delta,
        asserted_added=tuple(map(text_of, delta.asserted_added)),
        asserted_removed=tuple(map(text_of, delta.asserted_removed)),
        inferred_added=tuple(map(text_of, delta.inferred_added)),
        inferred_removed=tuple(map(text_of, delta.inferred_removed)),
    )


def _applying(apply: Callable[[], Delta]) -> tuple[Delta, RuleLoopError | None]:
    """Run an engine update; on a rule loop return what it kept, and the loop to report."""
    try:
        return apply(), None
    except RuleLoopError as loop:
        assert loop.kept is not None
        return loop.kept, loop


def main(argv: list[str] | None = None, prog: str | None = None) -> int:
    """Run the reasoner (see `--help`)."""
    return run_agent(Reasoner, argv, prog)


if __name__ == "__main__":
    sys.exit(main())
