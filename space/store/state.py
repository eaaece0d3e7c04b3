"""One space's current state in memory, and how a changeset changes it.

The database is the durable record; this is the indexed copy that answers
template reads and SPARQL, and decides what a changeset really changes:
functional properties replace their old value, the later HLC timestamp wins,
and only net changes are logged and published.
"""

from __future__ import annotations

from collections.abc import Iterable

from rdflib import Graph
from rdflib.graph import ReadOnlyGraphAggregate
from rdflib.namespace import OWL, RDF
from rdflib.term import Node

from space.changeset import Changeset, hlc_key
from space.keys import ASSERTED, INFERRED
from space.memory import BulkMemory
from space.prefixes import PrefixMap
from space.store.db import Commit
from space.template import Template
from space.terms import Triple, from_nt, to_nt


class SpaceState:
    """The state of one space: an asserted and an inferred graph, and its sequence number."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.seq = 0
        self.prefixes = PrefixMap()
        # Two plain graphs (no named graphs; updated in bulk); SPARQL reads their union.
        self.stores = {ASSERTED: BulkMemory(), INFERRED: BulkMemory()}
        self.graphs: dict[str, Graph] = {g: Graph(store=m) for g, m in self.stores.items()}
        self.union = ReadOnlyGraphAggregate(list(self.graphs.values()))
        self._stamps: dict[tuple[Node, Node], str] = {}
        self._functional: set[Node] = set()

    def load(self, rows: Iterable[tuple[str, str, str, str, str]]) -> None:
        """Fill the state from database rows `(g, s, p, o, ts)`."""
        for g, s, p, o, ts in rows:
            triple = (from_nt(s), from_nt(p), from_nt(o))
            self.stores[g].put(triple)
            if ts:
                self._stamps[(triple[0], triple[1])] = ts
        self._functional = self._functional_properties()

    def _functional_properties(self) -> set[Node]:
        return {
            s for g in self.graphs.values() for s in g.subjects(RDF.type, OWL.FunctionalProperty)
        }

    def apply(self, cs: Changeset) -> tuple[Changeset, Commit] | None:
        """Apply a changeset; return the net changeset (with its seq) and its database commit.

        Returns None when nothing changes: the changeset is then not logged.
        """
        asserted, inferred = self.stores[ASSERTED], self.stores[INFERRED]
        stamp = cs.timestamp
        added = self._functional_additions(cs.added, stamp)
        removed, added = _net(asserted, cs.removed + added.replaced, added.kept)
        i_removed, i_added = _net(inferred, cs.inferred_removed, cs.inferred_added)
        new_prefixes = self.prefixes.update(cs.prefixes)
        if not (removed or added or i_removed or i_added or new_prefixes):
            return None
        net = Changeset(
            id=cs.id,
            agent=cs.agent,
            timestamp=stamp,
            cause=cs.cause,
            added=added,
            removed=removed,
            inferred_added=i_added,
            inferred_removed=i_removed,
            prefixes=new_prefixes,
            seq=self.seq + 1,
        )
        return net, self.install(net)

    def install(self, net: Changeset, payload: bytes | None = None) -> Commit:
        """Apply a net changeset exactly as given and take its seq; return its database commit.

        `apply` ends here; a follower store installs the leader's net changesets directly.
        """
        self.prefixes.update(net.prefixes)
        self.stores[ASSERTED].update(net.removed, net.added)
        self.stores[INFERRED].update(net.inferred_removed, net.inferred_added)
        every = (*net.removed, *net.added, *net.inferred_removed, *net.inferred_added)
        if any(t[2] in _FUNCTIONAL_CLASS and t[1] == RDF.type for t in every):
            self._functional = self._functional_properties()
        for t in net.removed:
            self._stamps.pop((t[0], t[1]), None)
        # Each triple's texts once, for the database rows and the payload alike.
        added, removed, i_added, i_removed = (
            [_row(t) for t in triples]
            for triples in (net.added, net.removed, net.inferred_added, net.inferred_removed)
        )
        stamped = []
        for t, row in zip(net.added, added, strict=True):
            stamp = net.timestamp if t[1] in self._functional else ""
            if stamp:
                self._stamps[(t[0], t[1])] = stamp
            stamped.append((ASSERTED, row, stamp))
        self.seq = net.seq
        if payload is None:
            payload = net.encode(texts=(added, removed, i_added, i_removed))
        commit = Commit(space=self.name, seq=net.seq, payload=payload, prefixes=net.prefixes)
        commit.removed = [(ASSERTED, row) for row in removed] + [
            (INFERRED, row) for row in i_removed
        ]
        commit.added = stamped + [(INFERRED, row, "") for row in i_added]
        return commit

    def _functional_additions(self, added: list[Triple], stamp: str) -> _Additions:
        """Split additions into those kept and the old values they replace."""
        result = _Additions()
        latest: dict[tuple[Node, Node], Triple] = {}
        for t in added:
            if t[1] in self._functional:
                latest[(t[0], t[1])] = t  # within one changeset the last value wins
            else:
                result.kept.append(t)
        asserted = self.stores[ASSERTED]
        for (s, p), t in latest.items():
            held = self._stamps.get((s, p))
            if held and stamp and hlc_key(stamp) < hlc_key(held):
                continue  # an older write of a functional property loses, everywhere
            result.kept.append(t)
            result.replaced.extend((s, p, o) for o in asserted.objects_of(s, p) if o != t[2])
        return result

    def match(self, template: Template, graph: str = "all") -> list[Triple]:
        """Return the triples that match a template in one graph or both (no duplicates)."""
        pattern = template.pattern()
        graphs = list(self.graphs.values()) if graph == "all" else [self.graphs[graph]]
        seen: dict[Triple, None] = {}
        check = bool(template.variables())
        for g in graphs:
            for t in g.triples(pattern):
                if not check or template.match(t) is not None:
                    seen[t] = None
        return list(seen)

    def match_by_graph(self, template: Template) -> dict[str, list[Triple]]:
        """Return the matching triples of each graph, keyed `t` (asserted) and `i` (inferred)."""
        return {g: self.match(template, g) for g in self.graphs}


class _Additions:
    def __init__(self) -> None:
        self.kept: list[Triple] = []
        self.replaced: list[Triple] = []


def _net(
    graph: BulkMemory, removed: list[Triple], added: list[Triple]
) -> tuple[list[Triple], list[Triple]]:
    """Return what removing then adding really changes in a graph."""
    has = graph.has
    gone = {t: None for t in removed if has(t)}
    new = {t: None for t in added if not has(t) or t in gone}
    return [t for t in gone if t not in new], [t for t in new if t not in gone]


_FUNCTIONAL_CLASS = {OWL.FunctionalProperty}


def _row(t: Triple) -> tuple[str, str, str]:
    return (to_nt(t[0]), to_nt(t[1]), to_nt(t[2]))
