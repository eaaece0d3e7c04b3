"""Changesets cut by subject, each part keyed by its predicates: what a scoped subscriber receives.

Besides each whole changeset on `@/changes`, the store publishes the part about
each subject on `@/changes/<s>/<p1>/<p2>/...`, its predicates in the key (sorted,
a long list cut into several parts, `GROUP`), with `prev`: for each of those
(subject, predicate) pairs, the seq of the previous changeset that had triples on
it. A subscriber that selects keys with key expressions (a robot's subjects,
`<...%23robot7_$*>/*/**`; a predicate, `*/**/<p>/**`) so receives its share of a
fleet's traffic only, Zenoh filtering before Python decodes, and a `prev` it has
not seen tells it a part went missing. One put a subject, not one a pair: a
reasoner's answer of 200 settings of one robot is a few puts, not 200. The
chunks are the terms' full N-Triples text, escaped, never compacted: a term's
key must not change when the space learns a prefix later. See docs/wire-format.md.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from functools import lru_cache

from rdflib.term import Node

from space.changeset import LISTS
from space.errors import MalformedPayload
from space.keys import escape
from space.terms import CACHED, to_nt

HEADER = ("v", "id", "agent", "ts", "cause", "seq", "lifespan")  # repeated in every part
# A changeset of BURST (subject, predicate) pairs or more is followed by its end
# (`keys.end_key`): a scoped subscriber delivers its parts of it as one change when the end
# comes, not part by part.
BURST = 8
# An end names its changeset's subjects, and its predicates, each up to this many chunks: a
# scoped subscriber sends it back only through its subscribers that may select a part of it.
NAMED = 256
# Bytes of predicate chunks in one part's key, at most. Zenoh routes a key against each
# subscriber's expression chunk by chunk (~3 us a chunk with 20 subscriptions, to declare a
# publisher as to put undeclared), and past ~100 chunks worse than linearly (200: 1.7 ms):
# 200 settings are 3 parts of ~70 predicates, not 200 puts nor one key of 11 KB.
GROUP = 4096

Part = dict  # a changeset map: the header of its changeset, the triples of one key
PartKey = tuple[str, str]  # (subject chunk, predicate chunk): a pair


def split(wire: Mapping) -> dict[PartKey, Part]:
    """Return the parts of a changeset map by (subject chunk, predicate chunk), in first-seen order.

    Raises:
        MalformedPayload: a listed triple is not three N-Triples terms.
    """
    head = header(wire)
    lists = cut(((name, _listed(wire, name)) for name in LISTS), chunks)
    return {key: {**head, **listed} for key, listed in lists.items()}


def header(wire: Mapping) -> dict:
    """Return what of a changeset map every one of its parts repeats (`HEADER`)."""
    return {name: wire[name] for name in HEADER if name in wire}


def cut(
    lists: Iterable[tuple[str, Sequence[Sequence[str]]]],
    key: Callable[[Sequence[str]], PartKey],
) -> dict[PartKey, dict[str, list]]:
    """Return each part's triple lists by its `key`, from a changeset's (name, triples) lists."""
    parts: dict[PartKey, dict[str, list]] = {}
    for name, listed in lists:
        for triple in listed:
            k = key(triple)
            part = parts.get(k)
            if part is None:
                parts[k] = {name: [triple]}
            elif name in part:
                part[name].append(triple)
            else:
                part[name] = [triple]
    return parts


# A term's key chunk, each text escaped once: a changeset's keys repeat their terms (one
# subject for 200 settings), and escaping was most of the store's cutting.
_chunk = lru_cache(maxsize=CACHED)(escape)


def grouped(
    pairs: Mapping[PartKey, dict[str, list]],
) -> list[tuple[str, list[str], dict[str, list]]]:
    """Return a changeset's parts by subject: `(s, predicates, lists)`, from its pairs' lists.

    Each subject's predicates are sorted, so a key comes back when its pairs do (a
    declared publisher pays off), and cut where their chunks pass `GROUP` bytes.
    """
    subjects: dict[str, list[str]] = {}
    for s, p in pairs:
        subjects.setdefault(s, []).append(p)
    out = []
    for s, predicates in subjects.items():
        group: list[str] = []
        size = 0
        for p in sorted(predicates):
            if group and size + len(p) > GROUP:
                out.append((s, group, _merged([pairs[(s, q)] for q in group])))
                group, size = [], 0
            group.append(p)
            size += len(p) + 1
        out.append((s, group, _merged([pairs[(s, q)] for q in group])))
    return out


def _merged(lists: list[dict[str, list]]) -> dict[str, list]:
    """Return the lists of several pairs as one part's (the first pair's lists when alone)."""
    if len(lists) == 1:
        return lists[0]
    merged: dict[str, list] = {}
    for listed in lists:
        for name, triples in listed.items():
            merged.setdefault(name, []).extend(triples)
    return merged


def end(seq: int, parts: Mapping[PartKey, object]) -> dict:
    """Return the end of a changeset of `parts` (its pairs): its seq and their chunks.

    Its subjects' chunks (`s`) and its predicates' (`p`), each list left out when
    longer than `NAMED`. A subscriber then sends it back only through those of its
    key expressions that match one of its subjects and one of its predicates
    (`space._scoped`).
    """
    out: dict = {"seq": seq}
    subjects = list(dict.fromkeys(s for s, _p in parts))
    predicates = list(dict.fromkeys(p for _s, p in parts))
    if len(subjects) <= NAMED:
        out["s"] = subjects
    if len(predicates) <= NAMED:
        out["p"] = predicates
    return out


def joined(parts: list[Part]) -> Part:
    """Return the parts of one changeset as one map: the first one's header, every one's triples.

    Raises:
        MalformedPayload: a part's triple list is not a list.
    """
    merged = {name: value for name, value in parts[0].items() if name not in LISTS}
    for part in parts:
        for name in LISTS:
            listed = _listed(part, name)
            if listed:
                merged.setdefault(name, []).extend(listed)
    return merged


def only(part: Part, predicates: set[str]) -> Part:
    """Return a part with the triples of the predicates given (their chunks) only.

    Raises:
        MalformedPayload: a listed triple is not three N-Triples terms.
    """
    kept = {name: value for name, value in part.items() if name not in LISTS}
    for name in LISTS:
        listed = [t for t in _listed(part, name) if chunks(t)[1] in predicates]
        if listed:
            kept[name] = listed
    return kept


def _listed(wire: Mapping, name: str) -> list:
    """Return a changeset map's list `name` (empty if absent).

    Raises:
        MalformedPayload: it is not a list.
    """
    listed = wire.get(name) or []
    if not isinstance(listed, list):
        raise MalformedPayload(f"'{name}' must be a list of triples")
    return listed


def made_chunks(triple: Sequence[str]) -> PartKey:
    """Return the key chunks of a triple the store made (its texts are N-Triples: not checked)."""
    return _chunk(triple[0]), _chunk(triple[1])


def chunks(triple: object) -> PartKey:
    """Return the key chunks of a wire triple's subject and predicate (their escaped text).

    Raises:
        MalformedPayload: not a list of three N-Triples terms.
    """
    if not isinstance(triple, list | tuple) or len(triple) != 3:
        raise MalformedPayload(f"a triple is a list of three terms, got {triple!r:.80}")
    s, p = triple[0], triple[1]
    if not isinstance(s, str) or not isinstance(p, str):
        raise MalformedPayload(f"a term is an N-Triples string, got {triple!r:.80}")
    return _chunk(s), _chunk(p)


def term_chunk(term: Node) -> str:
    """Return the chunk of a term in a part key."""
    return escape(to_nt(term))
