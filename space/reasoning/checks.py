"""Reject rules the engine could not run, when they are built rather than when they fire."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import replace
from typing import NoReturn

from rdflib import Literal

from space.reasoning.builtins import Effect, Place
from space.reasoning.errors import RuleError
from space.reasoning.rules import Call, Functor, Location, Pattern, Rule, Var, variables


def located(where: Location | None, rule_name: str | None, message: str) -> str:
    """Return `file:line:column: in rule 'name': message`, leaving out what is unknown."""
    parts = [f"{where}: " if where else "", f"in rule '{rule_name}': " if rule_name else ""]
    return "".join(parts) + message


def check_rule(rule: Rule) -> None:
    """Check arities, places, drop/remove indices and variable binding.

    Raises:
        RuleError: the first problem found, with its location and the rule's name.
    """
    bound: set[Var] = set()
    for item in rule.body:
        if isinstance(item, Pattern):
            _check_pattern(rule, item)
            bound.update(v for t in item.terms for v in variables(t))
        else:
            _check_call(rule, item, Place.BODY)
            bound.update(_outputs(item))
    for item in rule.body:
        if isinstance(item, Call) and not item.builtin.deferred:
            outputs = _outputs(item)
            for var in _call_vars(item):
                if var not in bound and var not in outputs:
                    _fail(
                        rule, item.where, f"{item.name}() needs {var} bound, but nothing binds it"
                    )
    for item in rule.head:
        if isinstance(item, Pattern):
            _check_pattern(rule, item)
            free = [v for t in item.terms for v in variables(t) if v not in bound]
        else:
            _check_call(rule, item, Place.HEAD)
            free = [v for v in _call_vars(item) if v not in bound]
            if item.builtin.effect is not Effect.NONE:
                _check_indices(rule, item)
        if free:
            _fail(rule, item.where, f"variable {free[0]} in the head is not bound by the body")


def mark_shared_names(
    rules: Iterable[Rule], warn: Callable[[str], None] | None = None
) -> list[Rule]:
    """Return the rules, those whose name another one has marked so their labels say where.

    Jena accepts a name used twice; firings and `why` then name each rule by name and
    `file:line`. `warn` is told of each later use, naming the first.
    """
    rules = list(rules)
    first: dict[str, Rule] = {}
    shared: set[str] = set()
    for rule in rules:
        if rule.name is None:
            continue
        if rule.name in first:
            shared.add(rule.name)
            if warn:
                where, before = rule.where or "<rule>", first[rule.name].where or "<rule>"
                warn(f"{where}: rule name '{rule.name}' is used again, first at {before}")
        else:
            first[rule.name] = rule
    return [
        replace(r, shared_name=True) if r.name in shared and not r.shared_name else r for r in rules
    ]


def _fail(rule: Rule, where: Location | None, message: str) -> NoReturn:
    raise RuleError(located(where or rule.where, rule.name, message))


def _outputs(call: Call) -> set[Var]:
    positions = call.builtin.outputs(len(call.args))
    return {a for i, a in enumerate(call.args) if i in positions and isinstance(a, Var)}


def _call_vars(call: Call) -> list[Var]:
    return [v for a in call.args for v in variables(a)]


def _check_pattern(rule: Rule, pattern: Pattern) -> None:
    for position, term in (("subject", pattern.s), ("predicate", pattern.p)):
        if isinstance(term, Functor):
            _fail(rule, pattern.where, f"a functor may only be an object, not the {position}")
    if isinstance(pattern.o, Functor) and any(isinstance(a, Functor) for a in pattern.o.args):
        _fail(rule, pattern.where, "nested functors are not supported")


def _check_call(rule: Rule, call: Call, place: Place) -> None:
    builtin = call.builtin
    if not builtin.accepts(len(call.args)):
        low, high = builtin.arity
        wanted = str(low) if low == high else f"{low} or more" if high is None else f"{low}-{high}"
        noun = "argument" if wanted == "1" else "arguments"
        _fail(rule, call.where, f"{call.name}() takes {wanted} {noun}, got {len(call.args)}")
    if place not in builtin.places:
        where = "body" if place is Place.BODY else "head"
        _fail(rule, call.where, f"{call.name}() cannot be used in a rule's {where}")
    problem = builtin.check(call.args)
    if problem:
        _fail(rule, call.where, f"{call.name}(): {problem}")


def _check_indices(rule: Rule, call: Call) -> None:
    last = len(rule.body) - 1
    has = {-1: "no items", 0: "only item 0"}.get(last, f"items 0..{last}")
    for arg in call.args:
        value = arg.value if isinstance(arg, Literal) else None
        if not isinstance(value, int) or isinstance(value, bool):
            _fail(rule, call.where, f"{call.name}() takes body item numbers, got {arg}")
        if not 0 <= value <= last:
            _fail(rule, call.where, f"{call.name}({value}): the body has {has}")
        if not isinstance(rule.body[value], Pattern):
            _fail(rule, call.where, f"{call.name}({value}): body item {value} is not a triple")
