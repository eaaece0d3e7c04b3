"""Build OWL 2 RL rules: the pattern and rule constructors and the list reader they share."""

from __future__ import annotations

from collections.abc import Sequence

from rdflib import OWL, RDF, Graph
from rdflib.collection import Collection
from rdflib.term import Node

from space.reasoning.builtins.compare import NotEqual
from space.reasoning.builtins.kinds import IsLiteral, NotLiteral
from space.reasoning.rules import Call, Item, Pattern, Rule, Term, Var

X, Y, Z = Var("x"), Var("y"), Var("z")
TYPE, SAME = RDF.type, OWL.sameAs


def p(s: Term, pred: Term, o: Term) -> Pattern:
    """Return a triple pattern."""
    return Pattern(s, pred, o)


def rule(name: str, body: Sequence[Item], head: Sequence[Item]) -> Rule:
    """Return a rule named as in the OWL 2 RL tables."""
    return Rule(name, tuple(body), tuple(head))


def not_literal(var: Var) -> Call:
    """Keep literals out of the subject position (OWL RL would put them there)."""
    return Call(NotLiteral(), (var,))


def is_literal(var: Var) -> Call:
    """Accept a literal only."""
    return Call(IsLiteral(), (var,))


def differ(a: Var, b: Var) -> Call:
    """Accept two different terms (by value)."""
    return Call(NotEqual(), (a, b))


def members(g: Graph, head: Node) -> list[Node]:
    """Return the members of an RDF list (empty for a malformed or missing one)."""
    if head == RDF.nil:
        return []
    return list(Collection(g, head))


def cardinality(g: Graph, r: Node, prop: Node) -> int | None:
    """Return the integer value of a cardinality restriction, or None."""
    value = g.value(r, prop)
    try:
        return None if value is None else int(value)
    except ValueError:
        return None
