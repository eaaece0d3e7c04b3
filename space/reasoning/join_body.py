"""Plan and emit one rule body's join, step by step, as the lines of a generated function.

`JoinBody` picks the join order (most-bound pattern first from the seed), binds
variables, inlines the common tests and places each builtin call as soon as its
inputs are bound; it also records the plan of the first steps (`joins.Plan`) that
`sharing` compares across rules. `joins.JoinCompiler` turns its lines into factories.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from space.reasoning.builtins import Effect
from space.reasoning.builtins.compare import Equal, NotEqual
from space.reasoning.checks import located
from space.reasoning.errors import RuleError
from space.reasoning.rules import Call, Functor, Pattern, Rule, Term, Var, variables

if TYPE_CHECKING:
    from space.reasoning.joins import JoinCompiler


_ACCESS = {
    # known (s, p, o) -> (rank, loop header template, positions bound by the loop)
    (True, True, True): (0, "", ()),
    (True, True, False): (1, "for {o} in SPO.get({s}, E).get({p}, E):", ("o",)),
    (True, False, True): (2, "for {p} in OSP.get({o}, E).get({s}, E):", ("p",)),
    (False, True, True): (3, "for {s} in POS.get({p}, E).get({o}, E):", ("s",)),
    (True, False, False): (
        4,
        "for {p}, {d} in SPO.get({s}, E).items():|for {o} in {d}:",
        ("p", "o"),
    ),
    (False, False, True): (
        5,
        "for {s}, {d} in OSP.get({o}, E).items():|for {p} in {d}:",
        ("s", "p"),
    ),
    (False, True, False): (
        6,
        "for {o}, {d} in POS.get({p}, E).items():|for {s} in {d}:",
        ("o", "s"),
    ),
    (False, False, False): (
        7,
        "for {s}, {d} in SPO.items():|for {p}, {e} in {d}.items():|for {o} in {e}:",
        ("s", "p", "o"),
    ),
}


@dataclass
class Source:
    """Accumulate the lines of one generated function."""

    lines: list[str] = field(default_factory=list)
    depth: int = 1
    loops: int = 0
    temps: int = 0

    def emit(self, line: str) -> None:
        self.lines.append("    " * self.depth + line)

    def open(self, header: str) -> None:
        self.emit(header)
        self.depth += 1
        self.loops += 1

    def skip(self) -> str:
        return "continue" if self.loops else "return"

    def temp(self) -> str:
        self.temps += 1
        return f"_t{self.temps}"


class _Cut(Exception):
    """The prefix of a join is emitted: stop planning."""


class JoinBody:
    """Plan and emit the join of one rule body from one seed item (or a part of it, `cut`)."""

    def __init__(
        self,
        compiler: JoinCompiler,
        rule: Rule,
        slots: dict[Var, int],
        cut: int | None = None,
        *,
        suffix: bool = False,
        tag: str = "",
    ) -> None:
        self.compiler = compiler
        self.cut = cut
        self.suffix = suffix
        self.tag = tag  # a name each match is appended beside (a batch's rule, `sharing`)
        self.keys: list[tuple[tuple, tuple[int, ...]]] = []  # the plan so far
        self.canon: dict[Var, int] = {}  # variables by first binding, as the plan numbers them
        self.shareable = True
        self.rule = rule
        self.slots = slots
        self.src = Source()
        self.bound: dict[Var, str] = {}
        self.premises: dict[int, str] = {}
        self.pattern_vars = {
            v
            for item in rule.body
            if isinstance(item, Pattern)
            for t in item.terms
            for v in variables(t)
        }

    def trigger(self, seed: int | None) -> list[str]:
        item = None if seed is None else self.rule.body[seed]
        patterns = {i: x for i, x in enumerate(self.rule.body) if isinstance(x, Pattern)}
        calls = {
            i: x
            for i, x in enumerate(self.rule.body)
            if isinstance(x, Call) and x.builtin.effect is Effect.NONE
        }
        if item is None:
            self.shareable = False
        elif isinstance(item, Pattern):
            self._seed(item.terms, seed)
            del patterns[seed]
            try:
                self._step("s", item.terms)
            except _Cut:
                return self.src.lines
        else:
            self.shareable = False
            # noValue(s, p[, o]) seeds what it names; countLiteralValues(s, p, n) s and p.
            counts = item.name == "countLiteralValues"
            seeded = (*item.args[:2], None) if len(item.args) == 2 or counts else item.args
            self._seed(tuple(_in_join(a, self.pattern_vars) for a in seeded), None)
        try:
            while True:
                self._place_calls(calls, deferred=False)
                if not patterns:
                    break
                index = min(patterns, key=lambda i: (self._rank(patterns[i]), i))
                self._pattern(patterns.pop(index), index)
        except _Cut:
            return self.src.lines
        self.shareable = False
        leftover = [c for c in calls.values() if not c.builtin.deferred]
        if leftover:
            message = f"cannot order the builtins {', '.join(c.name for c in leftover)}"
            raise RuleError(located(leftover[0].where, self.rule.name, message))
        self._place_calls(calls, deferred=True)
        premises = "".join(self.premises[i] + ", " for i in sorted(self.premises))
        values = [None] * len(self.slots)
        for var, slot in self.slots.items():
            values[slot] = self.bound.get(var, "None")
        match = f"(({premises}), ({''.join(f'{v}, ' for v in values)}))"
        self.src.emit(f"out.append(({self.tag}, {match}))" if self.tag else f"out.append({match})")
        return self.src.lines

    def _key(self, term: Term | None, constants: list[int]) -> tuple:
        """Name a term for the plan: a variable by when it was bound, a constant by its K."""
        if term is None:
            return ("_",)
        if isinstance(term, Var):
            return ("v", self.canon.setdefault(term, len(self.canon)))
        if isinstance(term, Functor):
            return ("f", term.name, *(self._key(a, constants) for a in term.args))
        constants.append(self.compiler.constants[term])
        return ("k",)

    def _step(self, kind: str, terms: tuple[Term | None, ...]) -> None:
        """Add a step to the plan; at the cut, end the prefix or start the suffix."""
        if not self.shareable:
            return
        constants: list[int] = []
        template = (kind, *(self._key(t, constants) for t in terms))
        self.keys.append((template, tuple(constants)))
        if len(self.keys) != self.cut:
            return
        ordered = [self.bound[v] for v in self.canon]
        if not self.suffix:
            premises = "".join(p + ", " for p in self.premises.values())
            values = "".join(v + ", " for v in ordered)
            self.src.emit(f"out.append((({premises}), ({values})))")
            raise _Cut
        self.src = Source(temps=self.src.temps)
        self.src.open("for _P, _V in partials:")
        for i, index in enumerate(self.premises):
            self.premises[index] = f"_p{i}"
        if self.premises:
            self.src.emit(f"{''.join(p + ', ' for p in self.premises.values())}= _P")
        for i, var in enumerate(self.canon):
            self.bound[var] = f"_v{i}"
        if self.canon:
            self.src.emit(f"{''.join(self.bound[v] + ', ' for v in self.canon)}= _V")

    def _expr(self, term: Term | None) -> str | None:
        """Return the source of a known term, or None if the join must find it."""
        if term is None or isinstance(term, Functor):
            return None
        if isinstance(term, Var):
            return self.bound.get(term)
        return self.compiler.constant(term)

    def _rank(self, pattern: Pattern) -> tuple[int, int]:
        """Rank by access path, then prefer joining on a bound variable over a class extent."""
        path = _ACCESS[tuple(self._expr(t) is not None for t in pattern.terms)][0]
        return path, -sum(1 for t in pattern.terms if isinstance(t, Var) and t in self.bound)

    def _seed(self, terms: tuple[Term | None, ...], index: int | None) -> None:
        exprs = []
        for term, incoming in zip(terms, ("s_", "p_", "o_"), strict=True):
            self._unify(term, incoming)
            exprs.append(incoming)
        if index is not None:
            self.premises[index] = f"({', '.join(exprs)})"

    def _pattern(self, pattern: Pattern, index: int) -> None:
        known = [self._expr(t) for t in pattern.terms]
        _, template, found = _ACCESS[tuple(k is not None for k in known)]
        names = dict(zip("spo", known, strict=True))
        for position in found:
            names[position] = self.src.temp()
        names["d"], names["e"] = self.src.temp(), self.src.temp()
        if template:
            for header in template.split("|"):
                self.src.open(header.format(**names))
        else:
            self.src.emit(f"if ({names['s']}, {names['p']}, {names['o']}) not in TRIPLES:")
            self.src.emit(f"    {self.src.skip()}")
        for position, term in zip("spo", pattern.terms, strict=True):
            if position in found:
                self._unify(term, names[position])
        self.premises[index] = f"({names['s']}, {names['p']}, {names['o']})"
        self._step("p", pattern.terms)

    def _unify(self, term: Term | None, expr: str) -> None:
        """Bind a new variable to `expr`, or check `expr` against what the term already is."""
        if term is None:
            return
        if isinstance(term, Functor):
            self._functor(term, expr)
            return
        known = self._expr(term)
        if known is None:
            self.bound[term] = expr  # type: ignore[index]
        else:
            self.src.emit(f"if {expr} != {known}:")
            self.src.emit(f"    {self.src.skip()}")

    def _functor(self, functor: Functor, expr: str) -> None:
        value = self.src.temp()
        self.src.emit(f"{value} = TERM({expr})")
        arity = len(functor.args)
        test = f"type({value}) is not FV or {value}.name != {functor.name!r}"
        self.src.emit(f"if {test} or len({value}.args) != {arity}:")
        self.src.emit(f"    {self.src.skip()}")
        for i, arg in enumerate(functor.args):
            self._unify(arg, f"{value}.args[{i}]")

    def _place_calls(self, calls: dict[int, Call], *, deferred: bool) -> None:
        for index in list(calls):
            call = calls[index]
            if call.builtin.deferred != deferred:
                continue
            outputs = call.builtin.outputs(len(call.args))
            inputs = [a for i, a in enumerate(call.args) if i not in outputs]
            if not deferred and any(self._expr(a) is None for a in inputs):
                continue
            del calls[index]
            self._call(call, index)

    def _call(self, call: Call, index: int) -> None:
        args = []
        for arg in call.args:
            if isinstance(arg, Functor):
                raise RuleError(
                    located(call.where, self.rule.name, "functors cannot be builtin arguments")
                )
            args.append(self._expr(arg) or "None")
        if type(call.builtin) in _INLINE:
            # TermTable.same_value, inlined: the test most rules use, run on every join.
            a, b = args
            test = _INLINE[type(call.builtin)].format(a=a, b=b)
            self.src.emit(f"if {test}:")
            self.src.emit(f"    {self.src.skip()}")
            self._step(type(call.builtin).__name__, call.args)
            return
        self.shareable = False  # a builtin may not be a function of its arguments (makeTemp)
        name = f"B{index}"
        self.compiler.builtins.add(index)
        result = self.src.temp()
        self.src.emit(f"{result} = {name}(CTX, ({''.join(a + ', ' for a in args)}))")
        self.src.emit(f"if {result} is None:")
        self.src.emit(f"    {self.src.skip()}")
        for i, arg in enumerate(call.args):
            if (
                isinstance(arg, Var)
                and arg not in self.bound
                and i in call.builtin.outputs(len(call.args))
            ):
                local = self.src.temp()
                self.src.emit(f"{local} = {result}[{i}]")
                self.bound[arg] = local


_INLINE = {
    # builtin -> when a join must skip, given the ids of the two arguments
    Equal: "{a} != {b} and KEYS[{a}] != KEYS[{b}]",
    NotEqual: "{a} == {b} or KEYS[{a}] == KEYS[{b}]",
}


def _in_join(term: Term | None, pattern_vars: set[Var]) -> Term | None:
    """Keep a noValue argument unless it is a variable no pattern binds (a wildcard)."""
    return None if isinstance(term, Var) and term not in pattern_vars else term
