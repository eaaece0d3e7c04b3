"""Compile each shape of rule once per process, for every rule of that shape and every engine.

Rules that differ only in their constants have the same joins: the paper's
rules (one per setting), OWL RL's instance rules (one per axiom). Their code
is planned and compiled once, with the constants as parameters (`joins`), and
kept here by shape; an engine binds it to its store, its term ids and the
rules' builtins (`CompiledRule`, `space.reasoning.compile`). So a second
engine on the same rules, or a reload of them, plans and compiles nothing,
and a thousand same-shaped rules share one copy of the code (which also keeps
the interpreter's caches warm while they fire one after another).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from rdflib.term import Node

from space.reasoning.builtins import Effect
from space.reasoning.joins import Factory, JoinCompiler, Plan
from space.reasoning.rules import Call, Functor, Pattern, Rule, Term, Var, variables

_LIMIT = 20_000  # shapes kept; the oldest go first (a process that reloads forever)


@dataclass(frozen=True)
class RuleCode:
    """The compiled functions of one shape of rule, as factories (`joins.Factory`).

    `triggers` has one join per body item a change can start from: each pattern,
    and the `noValue` (production rules) and `countLiteralValues` (backward rules)
    calls, which start joins on removals. `args` builds the arguments of each head
    action and body guard, by item index. A rule is `production` when a builtin
    of it is not monotonic (the shape names each builtin's kind). `plans` has
    each pattern's join as steps, for sharing them with other rules (`sharing`).
    """

    production: bool
    triggers: dict[int, Factory]
    plans: dict[int, Plan]
    start: Factory | None
    heads: Factory
    head_args: dict[int, Factory]
    body_args: dict[int, Factory]


@dataclass(frozen=True)
class Shape:
    """A rule seen without its constants: `key` equal for rules compiled alike."""

    key: tuple
    constants: tuple[Node, ...]  # the distinct constants, the code's K0, K1, ...


_CODE: dict[tuple, RuleCode] = {}
_SPLIT: dict[tuple, tuple[Factory, Factory]] = {}
_BATCH: dict[tuple, tuple[Factory, tuple[int, ...]]] = {}


def shape(rule: Rule) -> Shape:
    """Return a rule's shape: its items with variables by slot, constants by K index, and
    what the engine plans by (builtins' kinds and effects)."""
    slots = slots_of(rule)
    constants: dict[Node, int] = {}

    def term(t: Term) -> tuple:
        if isinstance(t, Var):
            return ("v", slots[t])
        if isinstance(t, Functor):
            return ("f", t.name, *map(term, t.args))
        return ("k", constants.setdefault(t, len(constants)))

    def item(i: Pattern | Call) -> tuple:
        if isinstance(i, Pattern):
            return ("p", *map(term, i.terms))
        b = i.builtin
        plan = (type(b), b.name, b.monotonic, b.effect, b.deferred, b.outputs(len(i.args)))
        return ("c", plan, *map(term, i.args))

    key = (rule.backward, tuple(map(item, rule.body)), tuple(map(item, rule.head)))
    return Shape(key, tuple(constants))


def code_of(rule: Rule, form: Shape) -> RuleCode:
    """Return the code of a rule of shape `form`, compiling it the first time the shape is seen.

    Raises:
        RuleError: the rule's builtins cannot be ordered, or a functor is a builtin argument.
    """
    found = _CODE.get(form.key)
    if found is not None:
        return found
    compiler = _compiler(rule, form)
    production = any(not c.builtin.monotonic for c in calls(rule))
    joins = {i: compiler.trigger(i) for i in _seeds(rule, production)}
    code = RuleCode(
        production=production,
        triggers={i: factory for i, (factory, _) in joins.items()},
        plans={i: plan for i, (_, plan) in joins.items()},
        start=None if any(isinstance(i, Pattern) for i in rule.body) else compiler.trigger(None)[0],
        heads=compiler.heads(),
        head_args={
            i: compiler.args(c)
            for i, c in enumerate(rule.head)
            if isinstance(c, Call) and c.builtin.effect is Effect.NONE
        },
        body_args={
            i: compiler.args(c)
            for i, c in enumerate(rule.body)
            if isinstance(c, Call) and not c.builtin.monotonic
        },
    )
    _keep(_CODE, form.key, code)
    return code


def split_code(rule: Rule, form: Shape, seed: int, cut: int) -> tuple[Factory, Factory]:
    """Return the join from pattern `seed` cut after `cut` steps of its plan: prefix, suffix.

    Compiled the first time a shape is cut there, as `code_of`.
    """
    key = (form.key, seed, cut)
    found = _SPLIT.get(key)
    if found is None:
        compiler = _compiler(rule, form)
        found = (compiler.prefix(seed, cut), compiler.suffix(seed, cut))
        _keep(_SPLIT, key, found)
    return found


def batch_code(rule: Rule, form: Shape, seed: int, cut: int) -> tuple[Factory, tuple[int, ...]]:
    """Return the suffix of `split_code` for a batch of rules of this shape, and the
    constants each member gives it (`JoinCompiler.suffixes`).

    Compiled the first time a shape is batched there, as `code_of`.
    """
    key = (form.key, seed, cut)
    found = _BATCH.get(key)
    if found is None:
        found = _compiler(rule, form).suffixes(seed, cut)
        _keep(_BATCH, key, found)
    return found


def _compiler(rule: Rule, form: Shape) -> JoinCompiler:
    """Return the compiler of a rule of shape `form` (its constants as K0, K1... in order)."""
    return JoinCompiler(rule, slots_of(rule), {c: i for i, c in enumerate(form.constants)})


def _keep(cache: dict, key: tuple, value: object) -> None:
    """Remember compiled code; past `_LIMIT` entries the oldest go first."""
    if len(cache) >= _LIMIT:
        cache.pop(next(iter(cache)), None)
    cache[key] = value


def _seeds(rule: Rule, production: bool) -> Iterator[int]:
    """Yield the body items a change starts a join from (see `RuleCode`)."""
    for index, item in enumerate(rule.body):
        if isinstance(item, Pattern):
            yield index
        elif item.name == "countLiteralValues" and rule.backward:
            yield index
        elif item.name == "noValue" and production:
            yield index


def calls(rule: Rule) -> Iterator[Call]:
    """Yield the builtin calls of a rule, body then head."""
    for item in (*rule.body, *rule.head):
        if isinstance(item, Call):
            yield item


def slots_of(rule: Rule) -> dict[Var, int]:
    """Return each variable's position in a match's bindings: by first occurrence."""
    slots: dict[Var, int] = {}
    for item in (*rule.body, *rule.head):
        terms: Sequence[object] = item.terms if isinstance(item, Pattern) else item.args
        for t in terms:
            for var in variables(t):  # type: ignore[arg-type]
                slots.setdefault(var, len(slots))
    return slots
