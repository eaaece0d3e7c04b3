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
from dataclasses import replace
from decimal import Decimal

from rdflib import Literal

from space.reasoning.builtins import Builtin, Effect, Registry
from space.reasoning.builtins.javaregex import JavaRegexError, translate
from space.reasoning.checks import located
from space.reasoning.errors import RuleError
from space.reasoning.rules import Call, Functor, Item, Pattern, Rule, Term, Var, variables

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
    return replace(rule, body=(*body, *tests))  # keeps `shared_name`: the label stays


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


def regex_groups(rule: Rule) -> Rule:
    """Return the rule with each `regex` call given no more output arguments than its constant
    pattern has groups: Jena binds the groups it has and leaves the other variables unbound
    (a head then makes them blank nodes), where an output here must be bound or the call fails.
    """
    body: list[Item] = []
    for item in rule.body:
        if isinstance(item, Call) and item.name == "regex" and len(item.args) > 2:
            pattern = item.args[1]
            if isinstance(pattern, Literal):
                try:
                    groups = translate(str(pattern)).groups
                except JavaRegexError:
                    groups = len(item.args)  # refused with the reason when the rule is checked
                if len(item.args) - 2 > groups:
                    item = Call(item.builtin, item.args[: 2 + groups], item.where)
        body.append(item)
    return Rule(rule.name, tuple(body), rule.head, rule.where, rule.backward)


def blank_head_variables(rule: Rule, registry: Registry) -> Rule:
    """Return the rule with each head occurrence of a variable the body does not bind made a
    blank node, as Jena does: one per occurrence and match (a `makeSkolem` of the match)."""
    skolem = registry.get("makeSkolem")
    bound = _bound(rule)
    if skolem is None or all(_vars_bound(i, bound) for i in rule.head):
        return rule
    key = tuple(sorted(bound, key=lambda v: v.name))
    calls: list[Call] = []

    def blank(term: Term, where: object) -> Term:
        if isinstance(term, Functor):
            return Functor(term.name, tuple(blank(a, where) for a in term.args))
        if not isinstance(term, Var) or term in bound:
            return term
        var = Var(f" blank{len(calls)}")
        tag = Literal(f"{rule.label} {where} {len(calls)}")
        calls.append(Call(skolem, (var, tag, *key), item.where))
        return var

    head: list[Item] = []
    for item in rule.head:
        if isinstance(item, Pattern):
            s, p, o = (blank(t, item.where) for t in item.terms)
            item = Pattern(s, p, o, item.where)
        head.append(item)
    return Rule(rule.name, (*rule.body, *calls), tuple(head), rule.where, rule.backward)


def _bound(rule: Rule) -> set[Var]:
    bound: set[Var] = set()
    for item in rule.body:
        if isinstance(item, Pattern):
            bound.update(v for t in item.terms for v in variables(t))
        elif isinstance(item, Call):
            outputs = item.builtin.outputs(len(item.args))
            bound.update(a for i, a in enumerate(item.args) if i in outputs and isinstance(a, Var))
    return bound


def _vars_bound(item: Item, bound: set[Var]) -> bool:
    if not isinstance(item, Pattern):
        return True
    return all(v in bound for t in item.terms for v in variables(t))
