"""Run Jena rules and OWL RL over a changing set of triples, at the cost of what changes.

Two layers share one state. The monotonic layer (OWL RL compiled for the
ontology, plus rules without drop/remove/noValue) keeps the closure of the
asserted triples, adding by delta joins and deleting by DRed over recorded
derivations. The production layer (rules with drop/remove/noValue) fires once
per new match, one firing at a time, in rule order then most recent first,
each firing's changes fully applied (closure included) before the next.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from itertools import repeat
from pathlib import Path

from rdflib import OWL, BNode, Graph, URIRef
from rdflib.term import Node

from space._heap import collector_paused
from space.errors import InputError
from space.reasoning import seminaive
from space.reasoning.agenda import Agenda
from space.reasoning.builtins import Context, Registry, default_registry
from space.reasoning.bulk import read_ids
from space.reasoning.changes import ChangeLog
from space.reasoning.checks import check_rule, mark_shared_names
from space.reasoning.compile import CompiledRule, RuleIndex
from space.reasoning.delta import Delta, Firing
from space.reasoning.errors import RuleError, RuleLoopError
from space.reasoning.firing import EngineFirings
from space.reasoning.forms import value_patterns
from space.reasoning.joins import Match, environment
from space.reasoning.owl import owl_rules
from space.reasoning.parser import load_rules
from space.reasoning.rdffiles import rdf_graph, read_graph
from space.reasoning.reading import EngineReads
from space.reasoning.rules import Rule
from space.reasoning.support import Support
from space.reasoning.terms import TermTable
from space.reasoning.triples import T, TripleStore
from space.reasoning.withdraw import Withdrawals, withdrawable
from space.terms import Triple


class RuleEngine(EngineReads, EngineFirings):
    """Keep a set of triples closed under rules; update it incrementally.

    Args:
        rules: parsed rules, in file order (production rules fire in this order).
        ontology: the TBox: compiled to OWL RL rules (when `owl`) and loaded with the data.
        registry: the builtins rules may use (the default set when None).
        owl: whether to add the OWL RL rules for the ontology.
        max_firings: production firings one update may take before it is a loop.
        printer: where the `print` builtin writes.

    Raises:
        RuleError: a rule cannot be used.

    Not thread-safe: one owner calls `load`, then `apply`, from one thread.
    """

    def __init__(
        self,
        rules: Sequence[Rule] = (),
        ontology: Graph | Iterable[Triple] | None = None,
        *,
        registry: Registry | None = None,
        owl: bool = True,
        max_firings: int = 10_000,
        printer: Callable[[str], None] = print,
        terms: TermTable | None = None,
    ) -> None:
        self.registry = registry or default_registry()
        self.rules = tuple(mark_shared_names(rules))
        for rule in self.rules:
            check_rule(rule)
        runnable = [value_patterns(r, self.registry) for r in self.rules]
        tbox = ontology if isinstance(ontology, Graph) else rdf_graph(ontology or ())
        self.terms = TermTable() if terms is None else terms  # HybridEngine: shared
        self._store = TripleStore()
        self._ctx = Context(self.terms, self._store, printer)
        env = environment(self.terms, self._store, self._ctx)
        index = RuleIndex()
        everything = [*runnable, *(owl_rules(tbox) if owl else [])]
        with collector_paused():  # what it makes lives as long as the engine
            self._compiled = [index.add(self.terms, env, r, i) for i, r in enumerate(everything)]
            index.share(self._store.triples)
            self._same = self.terms.id(OWL.sameAs)
            index.gate(self._store.pos, self._same)
        self._index = index
        # Backward rules with noValue: their conclusions go when no match holds (as Jena's).
        held = [c.order for c in self._compiled if c.rule.backward and withdrawable(c)]
        self._withdrawals = Withdrawals(held) if held else None
        self._ontology = [self._encode(t) for t in tbox]
        self._asserted: set[T] = set()
        self._asserted_by: dict[T, tuple[int, tuple[T, ...]]] = {}
        self._support = Support()
        self._agenda = Agenda(max_firings, self._compiled)  # a rule's order is its index
        self._log = ChangeLog(self.terms, self._store, self._asserted)
        self._firings: list[Firing] = []
        self._out: list[Match] = []  # what a join finds, for `_replace`
        # Decodes a Firing's triples when read; bound once, not per firing.
        self._triple: Callable[[T], Triple] = self.terms.triple  # type: ignore[assignment]
        self._production = True
        self._loaded = False
        self._graph: Graph | None = None

    @classmethod
    def from_files(
        cls,
        rules: Iterable[str | Path] = (),
        ontology: Iterable[str | Path] = (),
        **options: object,
    ) -> RuleEngine:
        """Build an engine from rules files and ontology files (Turtle, RDF/XML, N-Triples...).

        Raises:
            RuleSyntaxError, RuleError: a rules file is invalid.
            InputError: an ontology file cannot be read or parsed.
        """
        registry = options.pop("registry", None) or default_registry()
        parsed = load_rules(rules, registry)  # type: ignore[arg-type]
        return cls(parsed, read_graph(ontology), registry=registry, **options)  # type: ignore[arg-type]

    def load(self, triples: Graph | Iterable[Triple] = ()) -> Delta:
        """Assert the initial state (with the ontology) and run the rules to a fixpoint.

        Raises:
            RuleError: the engine was loaded already (use `apply`).
            RuleLoopError: production rules did not settle; the state is loaded without
                their firings (see `apply`).
        """
        return self._load_ids(lambda: [self._encode(t) for t in triples])

    def load_files(self, paths: Iterable[str | Path]) -> Delta:
        """`load` RDF files (format from the suffix), read by Oxigraph straight into ids.

        Raises:
            InputError: a file is missing or malformed.
            RuleError, RuleLoopError: as `load`.
        """
        return self._load_ids(lambda: read_ids(paths, self.terms))

    def _load_ids(self, read: Callable[[], list[T]]) -> Delta:
        """`load` what `read` encodes, read once the engine is known fresh; semi-naively
        unless a rule fires match by match (`seminaive.eligible`)."""
        if self._loaded:
            raise RuleError("load() starts a new engine; this one is loaded, use apply()")
        triples = read()
        if not seminaive.eligible(self):
            return self._apply_ids(triples, [])
        delta = seminaive.materialise(self, self._ontology + triples)
        self._loaded = True
        return delta

    def apply(self, added: Iterable[Triple] = (), removed: Iterable[Triple] = ()) -> Delta:
        """Retract `removed`, assert `added`, run the rules; return the net change.

        Removing a triple that is only inferred changes nothing: it holds as long
        as its support does. The first call on an engine not loaded loads the ontology.

        Raises:
            InputError: a triple is not three rdflib terms (IRI or blank node subject,
                IRI predicate).
            RuleLoopError: production rules kept firing. Their firings are undone; the
                caller's triples and what the monotonic rules draw from them are kept,
                and the error's `kept` is that net change, to publish like any delta.
        """
        return self._apply_ids([self._encode(t) for t in added], [self._encode(t) for t in removed])

    def apply_texts(
        self, added: Iterable[Sequence[str]] = (), removed: Iterable[Sequence[str]] = ()
    ) -> Delta:
        """`apply` on triples given as N-Triples texts; the `Delta`'s triples are texts too.

        For a caller that keeps terms in their wire form (the reasoner agent): a term is
        parsed once, when the engine first meets it, and no rdflib term is made for the
        rest. Every triple is encoded before the state changes.

        Raises:
            MalformedPayload: a text is not an N-Triples term (the state is unchanged).
            RuleLoopError: as `apply`; its `kept` in texts.
        """
        encode = self.terms.encode_texts
        return self._apply_ids(encode(added), encode(removed), texts=True)

    def _apply_ids(self, plus: list[T], minus: list[T], *, texts: bool = False) -> Delta:
        """`apply` on encoded triples (a HybridEngine passes its forward layer's changes);
        with `texts`, the `Delta`'s triples are N-Triples texts."""
        if not self._loaded:
            plus = self._ontology + plus
        self._log.begin(plus, minus)
        self._firings.clear()
        self._agenda.reset()
        try:
            self._unassert(minus, notify=True)
            self._assert(plus, None)
            if not self._loaded:
                self._start()
            self._run_agenda()
            if self._withdrawals is not None:
                self._withdraw()
        except RuleLoopError as loop:
            self._undo()
            loop.kept = self._apply_monotonic(plus, minus, texts)
            raise
        except Exception:
            self._undo()
            raise
        self._loaded = True
        return self._log.delta(tuple(self._firings), texts=texts)

    def _apply_monotonic(self, plus: list[T], minus: list[T], texts: bool) -> Delta:
        """Apply a change with production rules off: after a loop, the caller's triples stay."""
        self._log.begin(plus, minus)
        self._firings.clear()
        self._production = False
        try:
            self._unassert(minus, notify=True)
            self._assert(plus, None)
        finally:
            self._production = True
            self._agenda.reset()
        self._loaded = True
        self._graph = None
        return self._log.delta((), texts=texts)

    def _encode(self, triple: Triple) -> T:
        if not isinstance(triple, tuple | list) or len(triple) != 3:
            raise InputError(f"a triple is three terms, got {triple!r}")
        s, p, o = triple
        if (
            not isinstance(s, URIRef | BNode)
            or not isinstance(p, URIRef)
            or not isinstance(o, Node)
        ):
            raise InputError(f"not an RDF triple of rdflib terms: {triple!r}")
        term = self.terms.id
        return (term(s), term(p), term(o))

    def _assert(self, triples: Iterable[T], by: tuple[int, tuple[T, ...]] | None) -> None:
        """Assert triples and propagate through the monotonic rules."""
        asserted, touch, journal, add = (
            self._asserted,
            self._log.touch,
            self._log.journal,
            self._store.add,
        )
        queue = []
        for t in triples:
            if t in asserted:
                continue
            touch(t)
            asserted.add(t)
            journal += (True, t, by)  # flat: no tuple kept per entry
            if by is not None:
                self._asserted_by[t] = by
            if add(t):
                queue.append(t)
        if queue:
            self._propagate(queue)

    def _start(self) -> None:
        """Fire the rules whose body has no triple (axioms, builtins only) once, at load."""
        out: list[Match] = []
        queue: list[T] = []
        for compiled in self._compiled:
            if compiled.start is None:
                continue
            compiled.start(0, 0, 0, out)
            if out:
                self._take(compiled, out, queue)
        if queue:
            self._propagate(queue)

    def _propagate(self, queue: list[T]) -> None:
        """Run the joins each new triple starts until nothing new is derived."""
        starts, take = self._index.starts, self._take
        out: list[Match] = []
        position = 0
        while position < len(queue):
            s, p, o = queue[position]
            position += 1
            for compiled, trigger in starts(p, o):
                trigger(s, p, o, out)
                if out:
                    take(compiled, out, queue)

    def _take(self, compiled: CompiledRule | None, out: list, queue: list[T]) -> None:
        """Take what a join found (and empty `out`): production matches wait on the agenda,
        a monotonic rule's conclusions are derived, those new to the state onto `queue`."""
        if compiled is None:  # a batch of production rules (`sharing`)
            if self._production:
                self._agenda.push(out)
        elif compiled.production:
            if self._production:
                self._agenda.push(zip(repeat(compiled), out))
        else:
            self._derive(compiled, out, queue)
        out.clear()

    def _derive(self, compiled: CompiledRule, matches: list[Match], queue: list[T]) -> None:
        """Record what a monotonic rule concludes from `matches`; queue the heads new to the state.

        Apart from `_propagate`, whose production firings (one new triple each) need
        none of this.
        """
        store, triples, support, ctx = self._store, self._store.triples, self._support, self._ctx
        touch, order = self._log.touch, compiled.order
        for premises, bindings in matches:
            for head in compiled.heads(bindings):
                support.record(head, order, premises)
                if head not in triples:
                    touch(head)
                    store.add(head)
                    queue.append(head)
            for builtin, args in compiled.actions:
                builtin.act(ctx, args(bindings))

    def _unassert(self, triples: Iterable[T], *, notify: bool) -> None:
        """Retract asserted triples and what they alone supported.

        With `notify` (remove, a caller's removal) the retraction may activate
        rules whose noValue now holds; without it (drop) it is silent.
        """
        asserted, touch, journal, by = (
            self._asserted,
            self._log.touch,
            self._log.journal,
            self._asserted_by,
        )
        doomed = []
        for t in triples:
            if t not in asserted:
                continue
            touch(t)
            asserted.discard(t)
            journal += (False, t, by.pop(t, None))
            doomed.append(t)
        if not doomed:
            return
        gone = self._support.retract(doomed, self._store, asserted, touch)
        if not (notify and self._production):
            return
        out: list[Match] = []
        for s, p, o in gone:
            for compiled, trigger in self._index.on_removed(p):
                trigger(s, p, o, out)
                self._agenda.push(zip(repeat(compiled), out))
                out.clear()

    def _withdraw(self) -> None:
        """Retract what backward rules with noValue concluded from matches that hold no more."""
        assert self._withdrawals is not None
        while stale := self._withdrawals.stale(self._store.triples, self._asserted, self._ctx):
            self._unassert(stale, notify=True)
            self._run_agenda()

    def _undo(self) -> None:
        """Reverse this update's assertions and retractions, with production rules off."""
        journal = self._log.journal
        entries = [journal[i : i + 3] for i in range(0, len(journal), 3)]
        self._production = False
        try:
            for was_added, t, by in reversed(entries):
                if was_added:
                    self._unassert([t], notify=False)
                else:
                    self._assert([t], by)
        finally:
            self._production = True
            self._agenda.reset()
