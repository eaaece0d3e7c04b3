"""Materialise a fresh engine semi-naively: rounds over what is new, each match found once.

`RuleEngine.load` of monotonic rules (OWL RL and rules without
drop/remove/noValue) comes here. Each round joins only the triples new in the
round before (the delta) against the state, through the engine's own
compiled joins; the next round's delta is what they derived that was not
there. A triple enters the state just before its own joins run, so every
match of every body over the closure is found exactly once, from the premise
that entered last. The incremental path finds the same matches, but those
among loaded triples once per premise (all are stored before any join), and
keeps a journal and an undo log per triple; a load needs neither.

The engine ends in the state the incremental path reaches (the same triples,
asserted set and derivations, each triple one shared object), so later
updates are exact (DRed) as after any load. The cyclic garbage collector is
paused meanwhile: a load allocates millions of containers, none of them
garbage, that each collection would walk again (40% of a load's time).
"""

from __future__ import annotations

import gc
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

from space._heap import collector_paused
from space.reasoning.delta import Delta
from space.reasoning.joins import Match
from space.reasoning.rules import Pattern
from space.reasoning.support import Derivation, Entry
from space.reasoning.triples import SMALL, T

if TYPE_CHECKING:
    from space.reasoning.engine import RuleEngine


def eligible(engine: RuleEngine) -> bool:
    """Tell whether a load can go set-at-a-time: no rule fires one match at a time.

    Production rules fire in agenda order and builtin actions act in match
    order; both are orders the incremental path defines, so they keep it.
    """
    return engine._withdrawals is None and not any(
        c.production or c.actions for c in engine._compiled
    )


def materialise(engine: RuleEngine, plus: list[T]) -> Delta:
    """Assert `plus` (the ontology and the data, encoded) in a fresh engine and close it.

    Returns the load's `Delta`, as `ChangeLog.delta` gives it: every triple added.
    """
    with _collector_paused():
        try:
            order = _close(engine, plus)
        except BaseException:
            _empty(engine)  # as the incremental path undoes a failed update: nothing stays
            raise
        return engine._log.fresh(order)


def _empty(engine: RuleEngine) -> None:
    """Empty the state in place (compiled joins hold the store's dictionaries)."""
    store, support = engine._store, engine._support
    for held in (store.triples, store.spo, store.pos, store.osp, engine._asserted):
        held.clear()
    support.derivations.clear()
    support.dependents.clear()


def _close(engine: RuleEngine, plus: list[T]) -> list[T]:
    """Run the rounds; fill the store, the asserted set and the derivations.

    Returns every triple of the state in the order it arrived: the asserted
    ones in their order, then each round's derivations.
    """
    store, asserted = engine._store, engine._asserted
    add = store.add
    derivations: dict[T, Entry[Derivation]] = engine._support.derivations
    dependents: dict[T, Entry[T]] = engine._support.dependents
    starts = engine._index.starts
    # Each triple as the one object the store holds: derivations then share it,
    # not a copy per premise a join built (a third of the load's memory).
    canon: dict[T, T] = {}
    record = _recorders(engine, derivations, dependents, canon, fresh := {})
    delta = list(dict.fromkeys(plus))
    asserted.update(delta)
    order: list[T] = []
    out: list[Match] = []
    for compiled in engine._compiled:  # bodies without triples (axioms): once, first
        if compiled.start is not None:
            compiled.start(0, 0, 0, out)
            record[compiled.order](out)
            out.clear()
    delta.extend(t for t in fresh if t not in asserted)
    fresh.clear()
    while delta:
        # A triple of the round enters the state just before its joins run, so a
        # derivation is found once, from the premise that entered last (the
        # ontology, first in the load, finds no data: the data finds it).
        canon.update(zip(delta, delta, strict=True))
        order.extend(delta)
        for t in delta:
            add(t)
            s, p, o = t
            for compiled, trigger in starts(p, o):
                trigger(s, p, o, out)
                if out:
                    record[compiled.order](out)
                    out.clear()
        delta = list(fresh)
        fresh.clear()
    return order


def _recorders(
    engine: RuleEngine,
    derivations: dict[T, Entry[Derivation]],
    dependents: dict[T, Entry[T]],
    canon: dict[T, T],
    fresh: dict[T, T],
) -> dict[int, Callable[[list[Match]], None]]:
    """Compile, per rule, what records a batch of its matches and notes the new heads.

    Generated as source, as the joins are, with the heads and premises
    unrolled: this loop runs once per derivation, the load's most.
    """
    namespace: dict[str, object] = {
        "DER": derivations,
        "DEP": dependents,
        "CANON": canon,
        "FRESH": fresh,
        "SMALL": SMALL,
    }
    recorders = {}
    for compiled in engine._compiled:
        premises = sum(1 for item in compiled.rule.body if isinstance(item, Pattern))
        heads = sum(1 for item in compiled.rule.head if isinstance(item, Pattern))
        namespace[f"HEADS{compiled.order}"] = compiled.heads
        lines = [
            "def record(out):",
            "    for prem, b in out:",
            f"        prem = ({''.join(f'CANON[prem[{i}]], ' for i in range(premises))})",
            f"        d = ({compiled.order}, prem)",
            f"        hs = HEADS{compiled.order}(b)",
        ]
        for i in range(heads):
            lines.append(f"        h = hs[{i}]")
            lines.append("        h = CANON.get(h) or FRESH.setdefault(h, h)")
            lines.extend(_add("DER", "h", "d"))
            for j in range(premises):
                lines.extend(_add("DEP", f"prem[{j}]", "h"))
        scope: dict[str, object] = {}
        source = "\n".join(lines)
        exec(compile(source, f"<bulk record {compiled.label}>", "exec"), namespace, scope)
        recorders[compiled.order] = scope["record"]
    return recorders  # type: ignore[return-value]


def _add(mapping: str, key: str, item: str) -> list[str]:
    """Return the lines of `support.add(mapping, key, item)`, inlined: no call per derivation."""
    return [
        f"        held = {mapping}.get({key})",
        "        if held is None:",
        f"            {mapping}[{key}] = {item}",
        "        elif type(held) is tuple:",
        f"            if held != {item}:",
        f"                {mapping}[{key}] = [held, {item}]",
        "        elif type(held) is list:",
        f"            if {item} not in held:",
        "                if len(held) < SMALL:",
        f"                    held.append({item})",
        "                else:",
        f"                    {mapping}[{key}] = {{*held, {item}}}",
        "        else:",
        f"            held.add({item})",
    ]


@contextmanager
def _collector_paused() -> Iterator[None]:
    """Pause the cyclic garbage collector (if it runs) for a bulk build, then freeze.

    Freezing moves what the process holds (the new state above all) out of
    the collector's generations: it is long-lived, and the first collection
    after the load would otherwise walk all of it (13% of a load). Frozen
    objects are still freed when their last reference goes.
    """
    with collector_paused():
        try:
            yield
        finally:
            gc.freeze()
