"""Run Jena's head builtins that assert a triple per list entry, as ordinary rules.

`listMapAsSubject(L, p, o)` asserts `(x p o)` and `listMapAsObject(s, p, L)`
asserts `(s p x)` for each entry `x` of the RDF list `L`; `assertDisjointPairs(L)`
asserts `(x owl:differentFrom y)` for each two distinct entries. Here the call
becomes a head triple marking the list with a functor (which no listing shows),
and a few rules walk the list from the mark: the conclusions follow the list as
it grows, and go (as any monotonic conclusion) when the list or the rule's match goes.
"""

from __future__ import annotations

from collections.abc import Iterator

from rdflib import OWL, RDF, URIRef

from space.reasoning.builtins import Registry
from space.reasoning.builtins.listmap import ListMap
from space.reasoning.rules import Call, Functor, Item, Pattern, Rule, Var

_NS = "urn:x-tspace:jena-list#"
_SUBJECT, _OBJECT = URIRef(_NS + "mapAsSubject"), URIRef(_NS + "mapAsObject")
_NODE, _MEMBER = URIRef(_NS + "disjointNode"), URIRef(_NS + "disjointMember")
L, R, X, Y, P, OBJ, S, H = (Var(n) for n in ("l", "r", "x", "y", "p", "o", "s", "h"))


def expand_list_maps(rule: Rule, registry: Registry) -> Iterator[Rule]:
    """Yield the rule with its list-mapping calls as marks, then the rules that walk lists."""
    calls = [i for i in rule.head if isinstance(i, Call) and isinstance(i.builtin, ListMap)]
    if not calls:
        yield rule
        return
    head: list[Item] = [i for i in rule.head if i not in calls]
    walkers: list[Rule] = []
    for call in calls:
        name = f"{rule.name or 'rule'}/{call.name}"
        where = call.where
        if call.name == "listMapAsSubject":
            lst, p, o = call.args
            head.append(Pattern(lst, _SUBJECT, Functor("map", (p, o)), where))
            mark = Pattern(L, _SUBJECT, Functor("map", (P, OBJ)))
            walkers += _walk(name, mark, Pattern(R, _SUBJECT, mark.o), Pattern(X, P, OBJ), where)
        elif call.name == "listMapAsObject":
            s, p, lst = call.args
            head.append(Pattern(lst, _OBJECT, Functor("map", (s, p)), where))
            mark = Pattern(L, _OBJECT, Functor("map", (S, P)))
            walkers += _walk(name, mark, Pattern(R, _OBJECT, mark.o), Pattern(S, P, X), where)
        else:
            (lst,) = call.args
            head.append(Pattern(lst, _NODE, Functor("list", (lst,)), where))
            mark = Pattern(L, _NODE, Functor("list", (H,)))
            member = Pattern(X, _MEMBER, Functor("list", (H,)))
            walkers += _walk(name, mark, Pattern(R, _NODE, mark.o), member, where)
            other = Pattern(Y, _MEMBER, Functor("list", (H,)))
            not_equal = registry.get("notEqual")
            assert not_equal is not None
            different = Pattern(X, OWL.differentFrom, Y)
            walkers.append(
                Rule(name, (member, other, Call(not_equal, (X, Y))), (different,), where)
            )
    yield Rule(rule.name, rule.body, tuple(head), rule.where, rule.backward)
    yield from walkers


def _walk(
    name: str, mark: Pattern, next_mark: Pattern, entry: Pattern, where: object
) -> list[Rule]:
    """Return the two rules that follow a marked list: its first entry, and its rest."""
    first = Rule(name, (mark, Pattern(L, RDF.first, X)), (entry,), where)  # type: ignore[arg-type]
    rest = Rule(name, (mark, Pattern(L, RDF.rest, R)), (next_mark,), where)  # type: ignore[arg-type]
    return [first, rest]
