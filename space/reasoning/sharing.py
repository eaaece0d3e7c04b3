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
from itertools import pairwise
from typing import TYPE_CHECKING

from space.reasoning.joins import Factory, Partial, Plan, Trigger
from space.reasoning.rulecode import Shape, batch_code, split_code
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
    runs: tuple  # the rule's body builtins (B0, B1...)

    def steps(self) -> tuple[tuple, ...]:
        """Return the plan with the constants' term ids: equal for joins that start alike."""
        ids = self.ids.__getitem__
        return tuple((template, *map(ids, ks)) for template, ks in self.plan)


def share(candidates: list[Candidate], triples: set[T]) -> int:
    """Bind the candidates; those of a bucket that start alike share a prefix (`_groups`).

    Returns how many joins run a shared prefix.
    """
    buckets: dict[int, list[Candidate]] = {}
    for candidate in candidates:
        buckets.setdefault(id(candidate.bucket), []).append(candidate)
    shared = 0
    for members in buckets.values():
        batched: set[int] = set()  # positions a batch's leader runs for
        for prefix, group in _groups(members).items():
            batched.update(_rewire(group, len(prefix), triples))
            shared += len(group)
        bucket = members[0].bucket
        for member in members:
            if bucket[member.position][1] is None and member.position not in batched:
                bucket[member.position] = (member.compiled, member.bind(member.factory))
        if batched:
            bucket[:] = [entry for i, entry in enumerate(bucket) if i not in batched]
    return shared


def _groups(members: list[Candidate]) -> dict[tuple, list[Candidate]]:
    """Group members by a prefix they share (`_SHARED_STEPS` steps at least).

    Sorted, plans that share a prefix are neighbours, and a run of neighbours each
    sharing `depth` steps or more with the next all share `depth` steps. In each run
    of neighbours sharing `_SHARED_STEPS` or more, the depth is the one that saves the
    most steps (each neighbour it keeps together saves `depth`): two rules sharing
    five steps do not leave a third that shares their first three alone.
    """
    plans = sorted(((m.steps(), m.position, m) for m in members), key=lambda x: x[:2])
    common = [_common(a[0], b[0]) for a, b in pairwise(plans)]
    common.append(0)  # the last plan shares nothing with a next
    groups: dict[tuple, list[Candidate]] = {}
    start = 0
    for end, depth in enumerate(common):
        if depth >= _SHARED_STEPS:
            continue
        links = common[start:end]  # the run plans[start:end + 1]
        if links:
            cut = max(set(links), key=lambda d: (d * sum(x >= d for x in links), d))
            for plan, _, member in plans[start : end + 1]:
                groups.setdefault(plan[:cut], []).append(member)
        start = end + 1
    return {prefix: group for prefix, group in groups.items() if len(group) > 1}


def _common(a: tuple, b: tuple) -> int:
    """Return how many first steps two plans share."""
    common = 0
    for x, y in zip(a, b, strict=False):
        if x != y:
            break
        common += 1
    return common


class _Found:
    """What a group's prefix found for the triple being joined, and the store's size then."""

    __slots__ = ("partials", "size")

    def __init__(self) -> None:
        self.partials: list[Partial] = []
        self.size = -1


def _rewire(group: list[Candidate], cut: int, triples: set[T]) -> list[int]:
    """Bind the group's joins in their bucket: the leader's (the first), then its followers'.

    Returns the followers' positions when the group is one batch (`_batchable`): the
    leader's entry runs them all, theirs go.
    """
    group.sort(key=lambda m: m.position)
    leader = group[0]
    rule, form, seed = leader.compiled.rule, leader.form, leader.seed
    prefix = leader.bind(split_code(rule, form, seed, cut)[0])
    if _batchable(group):
        suffixes, used = batch_code(rule, form, seed, cut)
        members = tuple((m.compiled, tuple(m.ids[k] for k in used)) for m in group)
        batch = _batch(prefix, leader.bind(suffixes), members)
        leader.bucket[leader.position] = (None, batch)
        return [m.position for m in group[1:]]
    found = _Found()
    for member in group:
        suffix = member.bind(split_code(member.compiled.rule, member.form, member.seed, cut)[1])
        join = _join(prefix, suffix, found, triples, member is leader)
        member.bucket[member.position] = (member.compiled, join)
    return []


def _batchable(group: list[Candidate]) -> bool:
    """Tell whether one call can join the group: production rules (they change nothing
    while joins run), of one shape and builtins, side by side in their bucket."""
    leader = group[0]
    return all(
        m.compiled.production
        and m.form.key == leader.form.key
        and m.seed == leader.seed
        and m.runs == leader.runs
        and m.position == leader.position + i
        for i, m in enumerate(group)
    )


def _batch(prefix: Callable, suffixes: Callable, members: tuple) -> Trigger:
    """Return a batch's join: the prefix once, then every member's suffix in one call,
    each match as `(rule, match)`, in the members' (the bucket's) order."""
    partials: list[Partial] = []

    def join(s: int, p: int, o: int, out: list) -> None:
        partials.clear()  # first: a builtin that raised in the last call left its partials
        prefix(s, p, o, partials)
        if partials:
            suffixes(partials, out, members)

    return join


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
