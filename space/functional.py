"""Functional properties: writing `(s p o2)` replaces `(s p o1)`, in the same changeset.

One rule, used by every holder of a copy of the space (the store, the local
copies, `tspace reason`): within one batch of additions the last value of an
`(s, p)` wins, and the values already held for it are what it replaces.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from rdflib import OWL, RDF
from rdflib.term import Node

from space.terms import Triple

_TYPE, _FUNCTIONAL = RDF.type, OWL.FunctionalProperty  # looked up once: each is Python code


def declares_functional(triple: Triple) -> bool:
    """Return True if `triple` is `p rdf:type owl:FunctionalProperty`."""
    return triple[1] == _TYPE and triple[2] == _FUNCTIONAL


@dataclass
class Replacement:
    """What a batch of additions does to functional properties.

    Attributes:
        kept: the additions to apply, in order (earlier values of one functional
            `(s, p)` in the same batch left out).
        replaced: the held triples the kept values replace.
    """

    kept: list[Triple] = field(default_factory=list)
    replaced: list[Triple] = field(default_factory=list)


def replace_functional(
    added: Iterable[Triple],
    is_functional: Callable[[Node], bool],
    held: Callable[[Node, Node], Iterable[Node]],
) -> Replacement:
    """Return which additions to keep and which held triples they replace.

    Args:
        added: the triples being added.
        is_functional: whether a predicate is an owl:FunctionalProperty.
        held: the objects currently held for `(subject, predicate)`.

    Pure: reads through the two callables, changes nothing.
    """
    result = Replacement()
    latest: dict[tuple[Node, Node], Triple] = {}
    for triple in added:
        if is_functional(triple[1]):
            latest.pop((triple[0], triple[1]), None)
            latest[(triple[0], triple[1])] = triple
        else:
            result.kept.append(triple)
    for (s, p), triple in latest.items():
        result.kept.append(triple)
        result.replaced.extend((s, p, o) for o in held(s, p) if o != triple[2])
    return result
