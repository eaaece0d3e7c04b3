"""Rewrite Jena's other rule forms into the plain forward rules the engine runs.

- A rule nested in a head (`[p: (?p rdfs:domain ?c) -> [(?x rdf:type ?c) <- (?x ?p ?y)]]`,
  how Jena's OWL rule sets make instance rules) becomes one rule whose body is the
  parent's body then its own: it matches exactly when Jena's instance rule would
  exist and fire, and its conclusions go when the parent's match goes.
- A numeric literal in a body pattern, or a literal among a functor's arguments, is
  matched by value as Jena does (`1` matches `"1"^^xsd:integer` and `1.0`): it becomes
  a fresh variable and an `equal` test.
"""

from __future__ import annotations

from collections.abc import Iterator
from decimal import Decimal

from rdflib import Literal

from space.reasoning.builtins import Builtin, Effect, Registry
from space.reasoning.checks import located
from space.reasoning.errors import RuleError
from space.reasoning.rules import Call, Functor, Item, Pattern, Rule, Term, Var

_NUMBERS = (int, float, Decimal)


def flatten(rule: Rule) -> Iterator[Rule]:
    """Yield the rule without its nested rules, then one rule per nested rule (recursively).

    Raises:
        RuleError: a rule is nested in a body, or a nested rule drops or removes.
    """
    for item in rule.body:
        if isinstance(item, Rule):
            raise RuleError(located(item.where, rule.name, "a rule cannot be nested in a body"))
    nested = [i for i in rule.head if isinstance(i, Rule)]
    if not nested:
        yield rule
        return
    head = tuple(i for i in rule.head if not isinstance(i, Rule))
    if head:
        yield Rule(rule.name, rule.body, head, rule.where, rule.backward)
    for inner in nested:
        for item in inner.head:
            if isinstance(item, Call) and item.builtin.effect is not Effect.NONE:
                message = f"{item.name}() in a nested rule is not supported"
                raise RuleError(located(item.where, inner.name or rule.name, message))
        combined = Rule(
            inner.name or rule.name,
            (*rule.body, *inner.body),
            inner.head,
            inner.where,
            inner.backward,
        )
        yield from flatten(combined)


def value_patterns(rule: Rule, registry: Registry) -> Rule:
    """Return the rule with numeric body constants (objects, functor arguments) as value tests.

    The tests go after the body's items, so `drop`/`remove` numbers still name the same items.
    """
    equal = registry.get("equal")
    if equal is None:
        return rule
    tests: list[Call] = []
    body: list[Item] = []
    for item in rule.body:
        if isinstance(item, Pattern):
            o = _by_value(item.o, tests, equal, item)
            if o is not item.o:
                item = Pattern(item.s, item.p, o, item.where)
        body.append(item)
    if not tests:
        return rule
    return Rule(rule.name, (*body, *tests), rule.head, rule.where, rule.backward)


def _by_value(term: Term, tests: list[Call], equal: Builtin, item: Pattern) -> Term:
    if isinstance(term, Functor):
        args = tuple(_by_value(a, tests, equal, item) for a in term.args)
        return term if args == term.args else Functor(term.name, args)
    if isinstance(term, Literal) and _numeric(term):
        var = Var(f" value{len(tests)}")  # a space: no variable written in a file clashes
        tests.append(Call(equal, (var, term), item.where))
        return var
    return term


def _numeric(term: Literal) -> bool:
    value = term.value
    return isinstance(value, _NUMBERS) and not isinstance(value, bool)
