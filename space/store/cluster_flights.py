"""A replica's changesets in flight through etcd, and how one decided on another is chained.

A replica decides on what it applied plus its own changesets still in flight
(`ClusterSpace`). The guards `entry_for` makes say "unchanged since the
revision I applied", which a changeset of ours in flight on the same key
would break: a robot's next reading replaces the value its previous one
wrote. Such an entry is *chained*: it waits until the one it read commits,
its guard on that one's keys is raised to that revision (nobody else wrote
them in between, or that one's own guard would have failed), and it fails
when that one fails.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from space.store import oxterms
from space.store.cluster_entries import Decision, entry_for, logged_payload
from space.store.cluster_state import ClusterSpace
from space.store.etcd_log import Entry, Position
from space.store.state import Net
from space.store.writer import Request


@dataclass
class Flight:
    """A changeset of ours on its way through etcd, until applied here (or failed)."""

    req: Request
    state: ClusterSpace
    net: Net
    reply: Callable[[Net], dict]
    entry: Entry
    attempt: int
    request: str
    deps: set[int] = field(default_factory=set)  # ids of flights this one waits for
    waiting: list[Flight] = field(default_factory=list)
    position: Position | None = None
    over: bool = False  # applied or failed
    followers: list[Request] = field(default_factory=list)  # the same request id, sent again

    @property
    def writes(self) -> set[bytes]:
        """Return the keys this changeset writes."""
        return {*self.entry.puts, *self.entry.deletes, *self.entry.leased}


def guarded_entry(
    root: bytes,
    state: ClusterSpace,
    net: Net,
    revision: int,
    stamp: str,
    request: str,
    *,
    taken: bool,
    origin: str,
) -> Entry:
    """Return the log entry of a changeset decided at `revision`, guarded by what it read.

    `origin` names the writer that decided it (`logged_payload`).
    """
    functional = frozenset(oxterms.text(p) for p in state.functional_properties())
    add, rem, iadd, irem = ([tuple(t) for t in ts] for ts in net.texts)
    replaced = list(dict.fromkeys((t[0], t[1]) for t in (*add, *rem) if t[1] in functional))
    decision = Decision(
        space=state.name,
        payload=logged_payload(net.entry.payload, net.entry.dropped, origin),
        revision=revision,
        stamp=stamp,
        functional=functional,
        added=add,  # type: ignore[arg-type]
        removed=rem,  # type: ignore[arg-type]
        inferred_added=iadd,  # type: ignore[arg-type]
        inferred_removed=irem,  # type: ignore[arg-type]
        replaced=replaced,  # type: ignore[arg-type]
        taken=rem if taken else [],  # type: ignore[arg-type]
        prefixes=net.entry.prefixes,
        request=request,
    )
    return entry_for(root, decision)


def chain(flight: Flight, writers: dict[bytes, Flight]) -> bool:
    """Chain `flight` on our flights that write what it guards; return True if it may go now.

    `writers` maps each key to our latest flight writing it (not yet
    applied); `flight` becomes the latest writer of its own keys.
    """
    for key in {*flight.entry.guards, *flight.entry.present}:
        dep = writers.get(key)
        if dep is None or dep.over or dep is flight:
            continue
        if dep.position is not None:
            flight.entry.guards[key] = max(flight.entry.guards[key], dep.position.revision)
        elif id(dep) not in flight.deps:
            flight.deps.add(id(dep))
            dep.waiting.append(flight)
    for key in flight.writes:
        writers[key] = flight
    return not flight.deps


def committed(flight: Flight, position: Position) -> list[Flight]:
    """Record where `flight` committed; return the flights chained on it that may go now."""
    flight.position = position
    ready = []
    for w in flight.waiting:
        for key in flight.writes & {*w.entry.guards, *w.entry.present}:
            w.entry.guards[key] = max(w.entry.guards.get(key, 0), position.revision)
        w.deps.discard(id(flight))
        if not w.deps and not w.over:
            ready.append(w)
    flight.waiting = []
    return ready
