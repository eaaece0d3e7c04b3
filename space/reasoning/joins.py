"""Compile a rule body into Python join functions, one per pattern a new triple can match.

A trigger function starts from the changed triple (the pattern it matched binds
its variables), joins the other patterns most-bound first through the SPO/POS/OSP
indexes, and runs each builtin as soon as its inputs are bound. It appends
`(premises, bindings)` for every match to the list it is given. Generating the
nested loops as source and compiling them is what makes a join cost a few
microseconds instead of tens.

The source names no engine and no constant: each function is made by a factory
`make(ENV, K, B)` that binds the engine's store and context (`ENV`, see
`environment`), the rule's constants as term ids (`K<i>`, the i-th distinct
constant, `space.reasoning.rulecode`) and its body builtins (`B<i>`, body item i).
So the code is compiled once for every rule of the same shape and every engine.

A join can also be cut in two after its first steps (`prefix`, `suffix`), so that
rules whose joins start with the same steps run those steps once (`sharing`):
`plan` names each step canonically for that comparison.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from rdflib.term import Node

from space.reasoning.builtins import Context
from space.reasoning.join_body import JoinBody
from space.reasoning.rules import Call, Functor, Pattern, Rule, Term, Var
from space.reasoning.terms import FunctorValue, TermTable
from space.reasoning.triples import T, TripleStore

Match = tuple[tuple[T, ...], tuple[int | None, ...]]
Trigger = Callable[[int, int, int, list[Match]], None]
Heads = Callable[[tuple[int | None, ...]], tuple[T, ...]]
Factory = Callable[[tuple, tuple, tuple], Callable]
"""`make(ENV, K, B)`: one engine's function for one rule (see the module's docstring)."""
Plan = tuple[tuple[tuple, tuple[int, ...]], ...]
"""A join's first steps: the seed, patterns and inlined tests, in join order; each step as
its template (variables numbered by first binding, constants blank) and the K index of
each of its constants. Up to the first step no other rule could share (a builtin call:
it may not be a function of its inputs)."""
Partial = tuple[tuple[T, ...], tuple[int, ...]]
"""What a join's prefix found: its premises in join order, its variables in `Plan` order."""

_EMPTY: dict = {}
_ENV = "TRIPLES, SPO, POS, OSP, E, CTX, TERM, KEYS, FV, MKF"


def environment(terms: TermTable, store: TripleStore, ctx: Context) -> tuple:
    """Return what an engine's join functions use (`ENV`): its store, context and terms."""
    return (
        store.triples,
        store.spo,
        store.pos,
        store.osp,
        _EMPTY,
        ctx,
        terms.term,
        terms.keys,
        FunctorValue,
        lambda name, args: terms.id(FunctorValue(name, args)),
    )


class JoinCompiler:
    """Generate the factories of one rule's functions.

    Args:
        rule: the (checked) rule.
        slots: the position of each variable in a match's bindings.
        constants: the K index of each constant of the rule.
    """

    def __init__(self, rule: Rule, slots: dict[Var, int], constants: dict[Node, int]) -> None:
        self.rule = rule
        self.slots = slots
        self.constants = constants
        self.builtins: set[int] = set()  # the B<i> the function being generated calls

    def trigger(self, seed: int | None) -> tuple[Factory, Plan]:
        """Return the join that starts from a triple matching body item `seed`, and its plan.

        The seed is a pattern (the triple was added) or a `noValue` call (the
        triple was removed, so the call may now accept). With no seed, the join
        starts from nothing (an axiom, a body of builtins only) and ignores the triple.
        Only a pattern's join has a plan (the others are never shared).
        """
        gen = JoinBody(self, self.rule, self.slots)
        return self._define("_trigger", "s_, p_, o_, out", gen.trigger(seed)), tuple(gen.keys)

    def prefix(self, seed: int, cut: int) -> Factory:
        """Return the first `cut` steps of a pattern's join: it appends a `Partial` per match."""
        gen = JoinBody(self, self.rule, self.slots, cut, suffix=False)
        return self._define("_prefix", "s_, p_, o_, out", gen.trigger(seed))

    def suffix(self, seed: int, cut: int) -> Factory:
        """Return the rest of a pattern's join after `cut` steps: from `Partial`s to matches."""
        gen = JoinBody(self, self.rule, self.slots, cut, suffix=True)
        return self._define("_suffix", "partials, out", gen.trigger(seed))

    def suffixes(self, seed: int, cut: int) -> tuple[Factory, tuple[int, ...]]:
        """Return `suffix` for a batch of rules of this shape, in one call, and the K it reads.

        Each member is `(rule, constants)`, its term ids of those K in that order; every
        match is appended as `(rule, match)`, member after member.
        """
        gen = JoinBody(self, self.rule, self.slots, cut, suffix=True, tag="RULE")
        lines = gen.trigger(seed)
        used = tuple(sorted({int(k) for line in lines for k in re.findall(r"\bK(\d+)\b", line)}))
        body = [
            "    for RULE, K in members:",
            *([f"        {''.join(f'K{i}, ' for i in used)}= K"] if used else []),
            *("    " + line for line in lines),
        ]
        return self._define("_suffixes", "partials, out, members", body, constants=False), used

    def heads(self) -> Factory:
        """Return a function that instantiates the head patterns from bindings."""
        triples = [
            f"({', '.join(self._head_term(t) for t in item.terms)})"
            for item in self.rule.head
            if isinstance(item, Pattern)
        ]
        body = ["    return (" + "".join(t + ", " for t in triples) + ")"]
        return self._define("_heads", "b", body)

    def args(self, call: Call) -> Factory:
        """Return a function that builds a call's encoded arguments from bindings."""
        parts = [self._head_term(a) for a in call.args]
        return self._define("_args", "b", [f"    return ({''.join(p + ', ' for p in parts)})"])

    def constant(self, term: Node) -> str:
        """Return the name of a constant term in the generated code."""
        return f"K{self.constants[term]}"

    def _head_term(self, term: Term) -> str:
        if isinstance(term, Var):
            return f"b[{self.slots[term]}]"
        if isinstance(term, Functor):
            args = "".join(self._head_term(a) + ", " for a in term.args)
            return f"MKF({term.name!r}, ({args}))"
        return self.constant(term)

    def _define(
        self, name: str, params: str, body: list[str], *, constants: bool = True
    ) -> Factory:
        """Compile the factory of one function: it binds ENV, K (unless the function
        reads its `constants` itself) and B, then defines it."""
        lines = ["def make(ENV, K, B):", f"    {_ENV} = ENV"]
        if self.constants and constants:
            lines.append(f"    {''.join(f'K{i}, ' for i in range(len(self.constants)))}= K")
        lines += [f"    B{i} = B[{i}]" for i in sorted(self.builtins)]
        lines += [f"    def {name}({params}):", *("    " + line for line in body)]
        lines.append(f"    return {name}")
        self.builtins = set()
        scope: dict[str, object] = {}
        exec(compile("\n".join(lines), f"<rule join {name}>", "exec"), scope)
        return scope["make"]  # type: ignore[return-value]
