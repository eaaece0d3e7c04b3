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

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from space.reasoning.joins import Factory, Partial, Plan, Trigger
from space.reasoning.rulecode import Shape, split_code
from space.reasoning.triples import T

if TYPE_CHECKING:  # compile files the joins and imports this module
    from space.reasoning.compile import CompiledRule, Entry

_SHARED_STEPS = 3
"""The fewest steps a shared prefix has, the seed's included: one test saved per rule does
not pay for the calls a shared join adds (the project's OWL RL pairs, `prp-fp`)."""


@dataclass(slots=True)
class Candidate:
    """A pattern's join filed in an index bucket, bound once `share` knows if it shares."""

    bucket: list[Entry]
    position: int  # in the bucket, where a placeholder waits
    compiled: CompiledRule
    form: Shape
    seed: int  # the body item the join starts from
    plan: Plan
    ids: tuple[int, ...]  # the engine's term ids of the rule's constants (K0, K1...)
    factory: Factory  # the whole join
    bind: Callable[[Factory], Callable]  # the rule's code -> the engine's function

    def steps(self) -> tuple[tuple, ...]:
        """Return the plan with the constants' term ids: equal for joins that start alike."""
        ids = self.ids.__getitem__
        return tuple((template, *map(ids, ks)) for template, ks in self.plan)


def share(candidates: list[Candidate], triples: set[T]) -> int:
    """Bind the candidates; those of a bucket that start alike share their longest prefix.

    Returns how many joins run a shared prefix.
    """
    buckets: dict[int, list[Candidate]] = {}
    for candidate in candidates:
        buckets.setdefault(id(candidate.bucket), []).append(candidate)
    shared = 0
    for members in buckets.values():
        grouped = _groups(members) if len(members) > 1 else {}
        for prefix, group in grouped.items():
            if len(group) > 1:
                _rewire(group, len(prefix), triples)
                shared += len(group)
        for member in members:
            if member.bucket[member.position][1] is None:  # shares nothing
                member.bucket[member.position] = (member.compiled, member.bind(member.factory))
    return shared


def _groups(members: list[Candidate]) -> dict[tuple, list[Candidate]]:
    """Group members by the longest prefix each shares with another (`_SHARED_STEPS` at least).

    Sorted, a plan's longest common prefix with any other is with a neighbour.
    """
    plans = sorted(((m.steps(), m.position, m) for m in members), key=lambda x: x[:2])
    depths = [0] * len(plans)
    for i in range(1, len(plans)):
        a, b = plans[i - 1][0], plans[i][0]
        common = 0
        for x, y in zip(a, b, strict=False):
            if x != y:
                break
            common += 1
        depths[i - 1] = max(depths[i - 1], common)
        depths[i] = common
    groups: dict[tuple, list[Candidate]] = {}
    for (plan, _, member), depth in zip(plans, depths, strict=True):
        if depth >= _SHARED_STEPS:
            groups.setdefault(plan[:depth], []).append(member)
    return groups


class _Found:
    """What a group's prefix found for the triple being joined, and the store's size then."""

    __slots__ = ("partials", "size")

    def __init__(self) -> None:
        self.partials: list[Partial] = []
        self.size = -1


def _rewire(group: list[Candidate], cut: int, triples: set[T]) -> None:
    """Bind the group's joins in their bucket: the leader's (the first), then its followers'."""
    group.sort(key=lambda m: m.position)
    leader = group[0]
    prefix = leader.bind(split_code(leader.compiled.rule, leader.form, leader.seed, cut)[0])
    found = _Found()
    for member in group:
        suffix = member.bind(split_code(member.compiled.rule, member.form, member.seed, cut)[1])
        join = _join(prefix, suffix, found, triples, member is leader)
        member.bucket[member.position] = (member.compiled, join)


def _join(
    prefix: Callable, suffix: Callable, found: _Found, triples: set[T], leads: bool
) -> Trigger:
    """Return a member's join: the leader runs the prefix on each triple, a follower only
    when the store grew since (a monotonic rule's head, added between two members)."""
    partials = found.partials

    def join(s: int, p: int, o: int, out: list) -> None:
        if leads or len(triples) != found.size:
            partials.clear()
            prefix(s, p, o, partials)
            found.size = len(triples)
        if partials:
            suffix(partials, out)

    return join
