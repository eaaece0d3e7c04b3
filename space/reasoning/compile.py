"""Compile rules for one engine: join functions, head builders, and the index that finds them.

The index maps a triple to the joins it can start: by constant predicate and
object, by constant predicate, or (for patterns with a variable predicate) a
bucket every triple visits. A triple whose predicate no rule mentions costs a
few dictionary misses.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from rdflib.term import Node

from space.reasoning.builtins import Args, Builtin, Effect
from space.reasoning.joins import Heads, JoinCompiler, Trigger
from space.reasoning.rules import Call, Functor, Pattern, Rule, Var, variables

ArgsFn = Callable[[tuple], Args]


@dataclass(frozen=True)
class CompiledRule:
    """A rule ready to run: what it asserts, deletes and does once its body matched.

    `drops` and `removes` index the premises (the matched triples, in body order),
    not the body items. A rule is `production` when it drops, removes or uses
    `noValue` (any builtin that is not monotonic).
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


Entry = tuple[CompiledRule, Trigger]


class RuleIndex:
    """Find the joins a triple can start, when it is added or (for noValue) removed.

    A new triple `(s, p, o)` starts the joins of `by_po[(p, o)]`, `by_p[p]` and
    `anywhere`, which `starts` gives as one tuple.
    """

    def __init__(self) -> None:
        self.by_po: dict[tuple[int, int], list[Entry]] = {}
        self.by_p: dict[int, list[Entry]] = {}
        self.anywhere: list[Entry] = []
        self._removal_by_p: dict[int, list[Entry]] = {}
        self._removal_anywhere: list[Entry] = []
        self._starts: dict[tuple[int, int], tuple[Entry, ...]] = {}
        self._starts_by_p: dict[int, tuple[Entry, ...]] = {}

    def starts(self, p: int, o: int) -> tuple[Entry, ...]:
        """Return the joins a new triple with predicate `p` and object `o` starts, in order.

        Memoized per `(p, o)` pair a rule names, else per predicate: both are
        bounded by the rules and the vocabulary, never by the values written.
        """
        found = self._starts.get((p, o))
        if found is not None:
            return found
        found = self._starts_by_p.get(p)
        if found is None:
            found = self._starts_by_p[p] = (*self.by_p.get(p, ()), *self.anywhere)
        if (p, o) in self.by_po:
            found = self._starts[(p, o)] = (*self.by_po[(p, o)], *found)
        return found

    def on_removed(self, p: int) -> Iterator[Entry]:
        """Yield the joins whose noValue may accept since a triple with predicate `p` went."""
        yield from self._removal_by_p.get(p, ())
        yield from self._removal_anywhere

    def add(self, compiler: JoinCompiler, rule: Rule, order: int) -> CompiledRule:
        """Compile a (checked) rule and index its joins."""
        self._starts.clear()
        self._starts_by_p.clear()
        slots = _slots(rule)
        premise_of = {}
        for index, item in enumerate(rule.body):
            if isinstance(item, Pattern):
                premise_of[index] = len(premise_of)
        calls = [i for i in rule.head if isinstance(i, Call)]
        compiled = CompiledRule(
            rule=rule,
            label=rule.label,
            order=order,
            production=any(not c.builtin.monotonic for c in _calls(rule)),
            heads=compiler.heads(rule, slots),
            drops=_targets(calls, Effect.DROP, premise_of),
            removes=_targets(calls, Effect.REMOVE, premise_of),
            actions=tuple(
                (c.builtin, compiler.args(c, slots))
                for c in calls
                if c.builtin.effect is Effect.NONE
            ),
            guards=tuple(
                (c.builtin, compiler.args(c, slots))
                for c in rule.body
                if isinstance(c, Call) and not c.builtin.monotonic
            ),
            start=None if premise_of else compiler.trigger(rule, slots, None),
        )
        for index, item in enumerate(rule.body):
            if isinstance(item, Pattern):
                entry = (compiled, compiler.trigger(rule, slots, index))
                self._file(entry, item.p, item.o, compiler)
            elif item.name == "countLiteralValues" and rule.backward:
                # Jena counts again at each query: wake the rule on every addition and
                # removal with the counted predicate (what it concluded from an old count
                # is withdrawn, space/reasoning/withdraw.py).
                entry = (compiled, compiler.trigger(rule, slots, index))
                self._on_change(entry, item.args[1], compiler)
            elif item.name == "noValue" and compiled.production:
                entry = (compiled, compiler.trigger(rule, slots, index))
                predicate = item.args[1]
                if isinstance(predicate, Var | Functor):
                    self._removal_anywhere.append(entry)
                else:
                    key = compiler.constant(predicate)
                    self._removal_by_p.setdefault(key, []).append(entry)
        return compiled

    def _on_change(self, entry: Entry, p: object, compiler: JoinCompiler) -> None:
        if isinstance(p, Var | Functor):
            self.anywhere.append(entry)
            self._removal_anywhere.append(entry)
        else:
            key = compiler.constant(p)  # type: ignore[arg-type]
            self.by_p.setdefault(key, []).append(entry)
            self._removal_by_p.setdefault(key, []).append(entry)

    def _file(self, entry: Entry, p: object, o: object, compiler: JoinCompiler) -> None:
        if isinstance(p, Var | Functor):
            self.anywhere.append(entry)
        elif isinstance(o, Var | Functor):
            self.by_p.setdefault(compiler.constant(p), []).append(entry)  # type: ignore[arg-type]
        else:
            key = (compiler.constant(p), compiler.constant(o))  # type: ignore[arg-type]
            self.by_po.setdefault(key, []).append(entry)


def _calls(rule: Rule) -> Iterator[Call]:
    for item in (*rule.body, *rule.head):
        if isinstance(item, Call):
            yield item


def _slots(rule: Rule) -> dict[Var, int]:
    slots: dict[Var, int] = {}
    for item in (*rule.body, *rule.head):
        terms: Sequence[object] = item.terms if isinstance(item, Pattern) else item.args
        for term in terms:
            for var in variables(term):  # type: ignore[arg-type]
                slots.setdefault(var, len(slots))
    return slots


def _targets(calls: list[Call], effect: Effect, premise_of: dict[int, int]) -> tuple[int, ...]:
    targets: list[int] = []
    for call in calls:
        if call.builtin.effect is effect:
            targets.extend(premise_of[int(_value(a))] for a in call.args)
    return tuple(targets)


def _value(term: object) -> object:
    return term.toPython() if isinstance(term, Node) else term  # type: ignore[attr-defined]
