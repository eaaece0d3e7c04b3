"""Bind rules to one engine: join functions, head builders, and the index that finds them.

The code of each rule comes compiled from `rulecode` (once per shape of rule, per
process); binding it gives the engine's functions. The index maps a triple to the
joins it can start: by constant predicate and object, by constant predicate, or
(for patterns with a variable predicate) a bucket every triple visits. A triple
whose predicate no rule mentions costs a few dictionary misses.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

from rdflib import OWL, URIRef
from rdflib.term import Node

from space.reasoning.builtins import Args, Builtin, Effect
from space.reasoning.joins import Heads, Trigger
from space.reasoning.rulecode import code_of, shape
from space.reasoning.rules import Call, Functor, Pattern, Rule, Var
from space.reasoning.sharing import Candidate, share
from space.reasoning.terms import TermTable
from space.reasoning.triples import Index, T

ArgsFn = Callable[[tuple], Args]


@dataclass(frozen=True, slots=True)
class CompiledRule:
    """A rule ready to run: what it asserts, deletes and does once its body matched.

    `drops` and `removes` index the premises (the matched triples, in body order),
    not the body items. A rule is `production` when it drops, removes or uses
    `noValue` (any builtin that is not monotonic). It `replaces` when a firing only
    drops one premise and asserts one triple (no test, no other action): the engine's
    shortest firing path (`RuleEngine._replace`).
    """

    rule: Rule
    label: str
    order: int
    production: bool
    heads: Heads
    drops: tuple[int, ...]
    removes: tuple[int, ...]
    actions: tuple[tuple[Builtin, ArgsFn], ...]
    guards: tuple[tuple[Builtin, ArgsFn], ...]
    start: Trigger | None = None  # for a body without triples: its join, run at load
    replaces: bool = False


Entry = tuple[CompiledRule | None, Trigger]
"""A join and its rule; None for a batch of production rules (`sharing`), whose join
appends `(rule, match)` pairs."""
Memo = dict[tuple[int, int], tuple[Entry, ...]]


class RuleIndex:
    """Find the joins a triple can start, when it is added or (for noValue) removed.

    A new triple `(s, p, o)` starts the joins of `by_po[(p, o)]`, `by_p[p]` and
    `anywhere`, which `starts` gives as one tuple. The `anywhere` joins of OWL RL's
    equality rules (eq-rep-s/p/o: every triple wakes them) are left out while no
    `owl:sameAs` triple is stored (`gate`).
    """

    def __init__(self) -> None:
        self.by_po: dict[tuple[int, int], list[Entry]] = {}
        self._paired: set[int] = set()  # the predicates of `by_po`'s keys
        self.by_p: dict[int, list[Entry]] = {}
        self.anywhere: list[Entry] = []
        self._removal_by_p: dict[int, list[Entry]] = {}
        self._removal_anywhere: list[Entry] = []
        # Memos of `starts`: [0] without the gated `anywhere` joins, [1] with them.
        self._starts: tuple[Memo, Memo] = ({}, {})
        self._starts_by_p: tuple[dict[int, tuple[Entry, ...]], ...] = ({}, {})
        self._ungated: list[Entry] = self.anywhere  # but the joins `gate` holds back
        self._gate: int | None = None  # the predicate id (owl:sameAs) they need stored
        self._pos: Index = {}  # the store's POS index, where `starts` looks for it
        self._candidates: list[Candidate] = []  # joins that may share a prefix (`share`)
        self.shared = 0  # how many joins run a shared prefix

    def starts(self, p: int, o: int) -> tuple[Entry, ...]:
        """Return the joins a new triple with predicate `p` and object `o` starts, in order.

        Memoized per `(p, o)` pair a rule names, else per predicate: both are
        bounded by the rules and the vocabulary, never by the values written. A
        predicate no pair names is looked up first (a new setting's value: one lookup).
        Without the gated joins while their predicate has no triple: each of them
        would find nothing then, so the joins that run, and their order, are the same.
        """
        opened = self._gate in self._pos  # None (nothing gated) never is
        by_p = self._starts_by_p[opened]
        if p not in self._paired:  # no rule names an object with it: by predicate
            found = by_p.get(p)
            if found is not None:
                return found
        memo = self._starts[opened]
        found = memo.get((p, o))
        if found is not None:
            return found
        found = by_p.get(p)
        if found is None:
            anywhere = self.anywhere if opened else self._ungated
            found = by_p[p] = (*self.by_p.get(p, ()), *anywhere)
        if (p, o) in self.by_po:
            found = memo[(p, o)] = (*self.by_po[(p, o)], *found)
        return found

    def on_removed(self, p: int) -> Iterator[Entry]:
        """Yield the joins whose noValue may accept since a triple with predicate `p` went."""
        yield from self._removal_by_p.get(p, ())
        yield from self._removal_anywhere

    def add(self, terms: TermTable, env: tuple, rule: Rule, order: int) -> CompiledRule:
        """Bind a (checked) rule's code to an engine (`env`: `joins.environment`); index its joins.

        Raises:
            RuleError: the rule cannot be compiled.
        """
        self._forget_starts()
        form = shape(rule)
        code = code_of(rule, form)
        ids = tuple(map(terms.id, form.constants))
        runs = tuple(i.builtin.run if isinstance(i, Call) else None for i in rule.body)

        def bind(factory: Callable) -> Callable:
            return factory(env, ids, runs)

        premise_of = {}
        for index, item in enumerate(rule.body):
            if isinstance(item, Pattern):
                premise_of[index] = len(premise_of)
        heads = [i for i in rule.head if isinstance(i, Call)]
        drops = _targets(heads, Effect.DROP, premise_of)
        removes = _targets(heads, Effect.REMOVE, premise_of)
        replaces = (
            code.production
            and not rule.backward
            and len(drops) == 1
            and not removes
            and not code.head_args
            and not code.body_args
            and len(heads) == 1
            and sum(isinstance(i, Pattern) for i in rule.head) == 1
        )
        compiled = CompiledRule(
            rule=rule,
            label=rule.label,
            order=order,
            production=code.production,
            heads=bind(code.heads),
            drops=drops,
            removes=removes,
            actions=tuple((_builtin(rule.head[i]), bind(f)) for i, f in code.head_args.items()),
            guards=tuple((_builtin(rule.body[i]), bind(f)) for i, f in code.body_args.items()),
            start=None if code.start is None else bind(code.start),
            replaces=replaces,
        )
        for index, factory in code.triggers.items():
            item = rule.body[index]
            plan = code.plans[index]
            if isinstance(item, Pattern) and len(plan) > 1:  # bound by `share`
                bucket = self._file((compiled, None), item.p, item.o, terms)  # type: ignore[arg-type]
                where = len(bucket) - 1
                self._candidates.append(
                    Candidate(bucket, where, compiled, form, index, plan, ids, factory, bind, runs)
                )
                continue
            entry = (compiled, bind(factory))
            if isinstance(item, Pattern):
                self._file(entry, item.p, item.o, terms)
            elif item.name == "countLiteralValues":
                # Jena counts again at each query: wake the rule on every addition and
                # removal with the counted predicate (what it concluded from an old count
                # is withdrawn, space/reasoning/withdraw.py).
                self._on_change(entry, item.args[1], terms)
            elif isinstance(item.args[1], Var | Functor):  # noValue
                self._removal_anywhere.append(entry)
            else:
                key = terms.id(item.args[1])
                self._removal_by_p.setdefault(key, []).append(entry)
        return compiled

    def _on_change(self, entry: Entry, p: object, terms: TermTable) -> None:
        if isinstance(p, Var | Functor):
            self.anywhere.append(entry)
            self._removal_anywhere.append(entry)
        else:
            key = terms.id(p)  # type: ignore[arg-type]
            self.by_p.setdefault(key, []).append(entry)
            self._removal_by_p.setdefault(key, []).append(entry)

    def share(self, triples: set[T]) -> None:
        """Let joins that start alike share their prefix (`sharing`), once every rule is added:
        until then, the joins of patterns wait unbound. `shared` counts those that do.
        """
        self._forget_starts()
        self.shared += share(self._candidates, triples)
        self._candidates = []

    def gate(self, pos: Index, same: int) -> None:
        """Hold back the `anywhere` joins of rules with an `owl:sameAs` pattern while `pos`
        (the store's POS index) has no `owl:sameAs` triple; once every rule is shared.

        Such a join needs an `owl:sameAs` triple in the state to match, and the new
        triple that starts it is stored before it runs: skipped, it would have
        found nothing. (5 % of a firing's work at 200 rules, with no equality used.)
        """
        self._forget_starts()
        needs = [c is not None and _names(c.rule, OWL.sameAs) for c, _ in self.anywhere]
        self._ungated = [e for e, held in zip(self.anywhere, needs, strict=True) if not held]
        self._gate = same if any(needs) else None
        self._pos = pos

    def _forget_starts(self) -> None:
        for memo in (*self._starts, *self._starts_by_p):
            memo.clear()

    def _file(self, entry: Entry, p: object, o: object, terms: TermTable) -> list[Entry]:
        """File a join in its bucket; return the bucket."""
        if isinstance(p, Var | Functor):
            bucket = self.anywhere
        elif isinstance(o, Var | Functor):
            bucket = self.by_p.setdefault(terms.id(p), [])  # type: ignore[arg-type]
        else:
            key = (terms.id(p), terms.id(o))  # type: ignore[arg-type]
            bucket = self.by_po.setdefault(key, [])
            self._paired.add(key[0])
        bucket.append(entry)
        return bucket


def _names(rule: Rule, predicate: URIRef) -> bool:
    """Tell whether a body pattern of `rule` has `predicate` as its (constant) predicate."""
    return any(isinstance(i, Pattern) and i.p == predicate for i in rule.body)


def _targets(calls: list[Call], effect: Effect, premise_of: dict[int, int]) -> tuple[int, ...]:
    targets: list[int] = []
    for call in calls:
        if call.builtin.effect is effect:
            targets.extend(premise_of[int(_value(a))] for a in call.args)
    return tuple(targets)


def _builtin(item: object) -> Builtin:
    assert isinstance(item, Call)
    return item.builtin


def _value(term: object) -> object:
    return term.toPython() if isinstance(term, Node) else term  # type: ignore[attr-defined]
