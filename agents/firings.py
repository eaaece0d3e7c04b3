"""Records of rule firings in the space, so that people can see why the robot changed.

The firings that answer one changeset for one robot become one
`ac:RuleFiring` individual (`ac:firing_N`, or `ac:firing_ROBOT_N` from a
per-robot reasoner) naming the rules that fired (`ac:rule_names`, one literal:
their names, space-separated, in firing order), the changeset that caused them
and the robot they concerned: a record is six triples however many rules fired.
One triple a rule made a change that fired 200 rules write 200 triples of
bookkeeping and drop the oldest record's 200, half of the answer the store
commits. Only the last `keep` records stay in the space: the log is for the
HMI's "last rule firings", not an archive.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from datetime import UTC, datetime
from typing import TypeVar

from rdflib import XSD, Graph, Literal
from rdflib.term import Node

from agents.vocabulary import AC, RDF_TYPE, RECORD_PREFIX
from space import TextTriple, Triple, literal_nt, text_of, to_nt

AnyTriple = Triple | TextTriple
T = TypeVar("T", Triple, TextTriple)

FIRING_PREFIX = RECORD_PREFIX  # the subjects of firing records
RULE_NAMES = AC.rule_names


def rule_names(triples: Iterable[Triple]) -> list[str]:
    """Return the rule names the firing records among `triples` name, in their order."""
    return [name for _s, p, o in triples if p == RULE_NAMES for name in str(o).split()]


RECORD_TYPES = frozenset({AC.RuleFiring, AC.RuleLoop})


class _Texts:
    """The N-Triples texts of the terms a record is written with, made once."""

    type = to_nt(RDF_TYPE)
    firing, loop = to_nt(AC.RuleFiring), to_nt(AC.RuleLoop)
    rule_names, robot, cause = to_nt(RULE_NAMES), to_nt(AC.robot), to_nt(AC.cause)
    fired_at, firing_seq = to_nt(AC.fired_at), to_nt(AC.firing_seq)
    datetime, integer = str(XSD.dateTime), str(XSD.integer)


_RECORD_TEXTS = frozenset({_Texts.firing, _Texts.loop})  # RECORD_TYPES as the wire has them


def record_subjects(triples: Iterable[AnyTriple], *, texts: bool = False) -> set:
    """Return the firing records among the subjects of `triples`: those typed as one
    (with `texts`, triples and subjects as N-Triples texts).

    A record is written and dropped whole, its type with it, so the triples of one
    changeset (or a whole state) name their records themselves.
    """
    kinds, typed = (_RECORD_TEXTS, _Texts.type) if texts else (RECORD_TYPES, RDF_TYPE)
    return {s for s, p, o in triples if o in kinds and p == typed}  # the set first: fast


def without_records(triples: Iterable[T], *, texts: bool = False) -> list[T]:
    """Return the triples but those of firing records (the rules never need to see those);
    `texts` as for `record_subjects`."""
    triples = list(triples)
    records = record_subjects(triples, texts=texts)
    return [t for t in triples if t[0] not in records] if records else triples


class FiringLog:
    """The firing records this reasoner keeps in the space, oldest first.

    Its triples are N-Triples texts, as the reasoner's answers carry them: a record
    is written with no rdflib term made (`space.literal_nt`).
    """

    def __init__(self, keep: int = 100, prefix: str = FIRING_PREFIX) -> None:
        self.keep = keep
        self.prefix = prefix
        self.next = 1
        self._records: deque[list[TextTriple]] = deque()
        self._answering: tuple[str, str] | None = None  # (cause, robot's text)
        self._named: dict[str, None] = {}  # the rule names of the record being answered

    def restore(self, triples: Iterable[Triple]) -> None:
        """Take back this log's records from the space (rdflib terms, as read after a restart),
        numbering after them."""
        graph = Graph()
        for triple in triples:
            if str(triple[0]).startswith(self.prefix):
                graph.add(triple)
        numbered = []
        for record in set(graph.subjects()):
            seq = graph.value(record, AC.firing_seq)
            number = int(seq) if isinstance(seq, Literal) and str(seq).isdigit() else 0
            numbered.append((number, list(map(text_of, graph.triples((record, None, None))))))
        for number, triples_of in sorted(numbered, key=lambda item: item[0]):
            self._records.append(triples_of)  # type: ignore[arg-type]
            self.next = max(self.next, number + 1)

    def record(
        self, rules: Iterable[str], cause: str | None, robot: Node, when: datetime | None = None
    ) -> tuple[list[TextTriple], list[TextTriple]]:
        """Add the firings of `rules` for `robot`; return (triples to add, triples to drop).

        Firings with the same cause and robot as the last record join it: its
        `ac:rule_names` is replaced by one naming the new rules too.
        """
        named = dict.fromkeys(rules)
        robot_text = to_nt(robot)
        if cause and self._records and self._answering == (cause, robot_text):
            if named.keys() <= self._named.keys():
                return [], []
            self._named |= named
            record = self._records[-1]
            old = record[1]
            record[1] = (old[0], _Texts.rule_names, literal_nt(" ".join(self._named)))
            return [record[1]], [old]
        self._answering = (cause, robot_text) if cause else None
        self._named = named
        return self._new(_Texts.firing, named, cause, robot_text, when)

    def loop(
        self, rules: Iterable[str], cause: str | None, robot: Node, when: datetime | None = None
    ) -> tuple[list[TextTriple], list[TextTriple]]:
        """Add a record of a rule loop (`ac:RuleLoop`): the rules that kept firing, undone.

        Returns (triples to add, triples of records to drop), as `record` does.
        """
        self._answering = None
        return self._new(_Texts.loop, rules, cause, to_nt(robot), when)

    def _new(
        self,
        kind: str,
        rules: Iterable[str],
        cause: str | None,
        robot: str,
        when: datetime | None,
    ) -> tuple[list[TextTriple], list[TextTriple]]:
        iri, t = f"<{self.prefix}{self.next}>", _Texts
        fired_at = (when or datetime.now(UTC)).isoformat()  # rdflib's lexical form of it
        triples: list[TextTriple] = [  # the names second: `record` replaces them
            (iri, t.type, kind),
            (iri, t.rule_names, literal_nt(" ".join(rules))),
            (iri, t.robot, robot),
            (iri, t.fired_at, literal_nt(fired_at, t.datetime)),
            (iri, t.firing_seq, literal_nt(str(self.next), t.integer)),
        ]
        if cause:
            triples.append((iri, t.cause, literal_nt(cause)))
        self.next += 1
        self._records.append(triples)
        dropped: list[TextTriple] = []
        while len(self._records) > self.keep:
            dropped += self._records.popleft()
        return list(triples), dropped  # a copy: `record` may change the one kept
