"""Join once what several rules' joins start with: their shared prefix, once per triple.

Rules often share body patterns: the paper's rules all find a robot, its battery
and its mobile base before their own setting. Each pattern's join is a sequence of
steps (`joins.Plan`). Joins in one index bucket (started by the same triples) that
begin with the same steps, constants and variables' structure included, form a
group: the first of them in the bucket (the leader) runs the shared steps (the
prefix) and keeps what they found; each member, the leader too, runs only the rest
of its own join (the suffix) over that. The leader runs first on every triple (the
bucket's order); a member that finds the store changed since (a monotonic rule's
head, added between two members) joins the prefix again. So each rule gets the
matches, in the order, its whole join would give.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from space.reasoning.joins import Factory, Partial, Plan, Trigger
from space.reasoning.rulecode import Shape, split_code
from space.reasoning.triples import T

if TYPE_CHECKING:  # compile files the joins and imports this module
    from space.reasoning.compile import CompiledRule, Entry


@dataclass(frozen=True)
class Candidate:
    """A pattern's join filed in an index bucket, which could share its first steps."""

    bucket: list[Entry]
    position: int  # in the bucket
    compiled: CompiledRule
    form: Shape
    seed: int  # the body item the join starts from
    steps: Plan  # its plan, with the engine's term ids for constants (`concrete`)
    bind: Callable[[Factory], Callable]  # the rule's code -> the engine's function


def concrete(plan: Plan, ids: tuple[int, ...]) -> Plan:
    """Return a plan with each constant `("k", K index)` as the engine's `("k", term id)`."""

    def term(t: tuple) -> tuple:  # a step's kind and a call's name are strings: kept
        if t[0] == "k":
            return ("k", ids[t[1]])
        return ("f", t[1], *map(term, t[2:])) if t[0] == "f" else t

    return tuple(tuple(term(t) if type(t) is tuple else t for t in step) for step in plan)


def share(candidates: list[Candidate], triples: set[T]) -> int:
    """Group the candidates of each bucket by their longest shared prefix; rewire the buckets.

    Returns how many joins now run a shared prefix.
    """
    buckets: dict[int, list[Candidate]] = {}
    for candidate in candidates:
        buckets.setdefault(id(candidate.bucket), []).append(candidate)
    shared = 0
    for members in buckets.values():
        if len(members) > 1:
            shared += _share_bucket(members, triples)
    return shared


def _share_bucket(members: list[Candidate], triples: set[T]) -> int:
    names: dict[tuple, int] = {}
    plans = [tuple(names.setdefault(s, len(names)) for s in m.steps) for m in members]
    counts = Counter(plan[:depth] for plan in plans for depth in range(2, len(plan) + 1))
    groups: dict[tuple, list[Candidate]] = {}
    for member, plan in zip(members, plans, strict=True):
        depth = max((d for d in range(2, len(plan) + 1) if counts[plan[:d]] > 1), default=0)
        if depth:
            groups.setdefault(plan[:depth], []).append(member)
    shared = 0
    for prefix, group in groups.items():
        if len(group) > 1:
            _rewire(sorted(group, key=lambda m: m.position), len(prefix), triples)
            shared += len(group)
    return shared


class _Found:
    """What a group's prefix found for the triple being joined, and the store's size then."""

    __slots__ = ("partials", "size")

    def __init__(self) -> None:
        self.partials: list[Partial] = []
        self.size = -1


def _rewire(group: list[Candidate], cut: int, triples: set[T]) -> None:
    """Replace the group's joins in their bucket: the leader's, then its followers'."""
    leader = group[0]
    prefix = leader.bind(split_code(leader.compiled.rule, leader.form, leader.seed, cut)[0])
    found = _Found()
    for member in group:
        suffix = member.bind(split_code(member.compiled.rule, member.form, member.seed, cut)[1])
        run = _lead if member is leader else _follow
        member.bucket[member.position] = (member.compiled, run(prefix, suffix, found, triples))


def _lead(prefix: Callable, suffix: Callable, found: _Found, triples: set[T]) -> Trigger:
    partials = found.partials

    def lead(s: int, p: int, o: int, out: list) -> None:
        partials.clear()
        prefix(s, p, o, partials)
        found.size = len(triples)
        if partials:
            suffix(partials, out)

    return lead


def _follow(prefix: Callable, suffix: Callable, found: _Found, triples: set[T]) -> Trigger:
    partials = found.partials

    def follow(s: int, p: int, o: int, out: list) -> None:
        if len(triples) != found.size:  # a head was added since the leader's prefix
            partials.clear()
            prefix(s, p, o, partials)
            found.size = len(triples)
        if partials:
            suffix(partials, out)

    return follow
