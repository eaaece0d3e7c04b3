"""Gap-free change delivery: subscribe first, learn the store's sequence, fill gaps from its log.

Zenoh callbacks only hand payloads to a queue; a dispatcher thread per
`TripleSpace` orders them by sequence number, drops duplicates, fetches what
was missed, and calls the user's callbacks. A slow callback therefore delays
later changes but never blocks Zenoh. An owner that has a loop of its own (an
agent) runs the dispatching itself instead (`space._dispatch.Dispatcher(own_thread=False)`,
`deliver`): one thread hand-off less per change, and the callbacks run on the
thread that owns what they update.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import zenoh
from rdflib.term import Node
from zenoh.ext import AdvancedSubscriber

from space.changeset import Changeset, published_seq, unpack
from space.errors import MalformedPayload, SpaceError
from space.template import Template

if TYPE_CHECKING:
    from space._dispatch import Dispatcher

log = logging.getLogger("tspace.subscription")


@dataclass
class Change(Changeset):
    """The part of one changeset that matches a subscription's template."""

    bindings: list[dict[str, Node]] = field(default_factory=list)


Callback = Callable[[Change], None]


class Subscription:
    """One `subscribe()` to whole changesets: a template, a callback, the last seq delivered.

    `skip_agent` (a writer's name) leaves out that writer's changesets before
    their terms are parsed; with `texts`, the terms are not parsed at all: the
    changes carry N-Triples texts. Close it with `close()` (or `TripleSpace.unsubscribe`).
    """

    waiting = False  # whether a change received waits for more of its parts to be delivered

    def __init__(
        self,
        dispatcher: Dispatcher,
        template: Template,
        callback: Callback,
        *,
        skip_agent: str | None = None,
        texts: bool = False,
    ) -> None:
        self.template = template
        self.texts = texts
        self.callback = callback
        self.skip_agent = skip_agent
        self.last_seq = 0
        self.ready = False
        self.early: list[object] = []
        self.initial: Change | None = None
        self._dispatcher = dispatcher
        self._subscribers: list[zenoh.Subscriber | AdvancedSubscriber] = []

    def attach(self, subscriber: zenoh.Subscriber | AdvancedSubscriber) -> None:
        """Take ownership of a Zenoh subscriber that feeds this subscription."""
        self._subscribers.append(subscriber)

    def close(self) -> None:
        """Stop receiving changes; the callback is not called again."""
        subscribers, self._subscribers = self._subscribers, []
        with ExitStack() as steps:  # each runs even when another raised
            steps.callback(self._dispatcher.forget, self)
            for subscriber in subscribers:
                steps.callback(subscriber.undeclare)

    def item(self, sample: zenoh.Sample) -> object:
        """Return what the Zenoh callback queues for the dispatcher thread (None: nothing)."""
        return sample.payload.to_bytes()

    def delivered(self) -> None:
        """Note that what was received has been delivered: nothing waits any more."""

    def decode(self, payload: bytes) -> tuple[int, Changeset | None]:
        """Return a change's sequence number and changeset; None for a changeset skipped unparsed.

        Raises:
            MalformedPayload: not msgpack, not a published changeset (no id, no seq),
                or (if parsed) a term is invalid.
        """
        wire = unpack(payload)
        seq = published_seq(wire)
        assert isinstance(wire, dict)
        if self.skip_agent is not None and wire.get("agent") == self.skip_agent:
            return seq, None
        # Its seq, checked above, is read as it is.
        return seq, Changeset.from_wire(wire, texts=self.texts)

    def merge(self, into: object, item: object) -> bool:
        """Fold `item` into `into`, both waiting for delivery; False when they stay apart."""
        return False

    def change(self, item: object) -> Change | None:
        """Return the change to deliver for what `receive` returned (None: nothing)."""
        return item  # type: ignore[return-value]

    def receive(self, item: object, fetch: Fetch) -> list[Change]:
        """Return the changes to deliver for a received changeset, filling a gap before it.

        Raises:
            MalformedPayload: the payload is not a published changeset.
        """
        assert isinstance(item, bytes)
        seq, cs = self.decode(item)
        if seq <= self.last_seq:
            return []
        if seq == self.last_seq + 1:
            return self._advance(seq, cs)
        # A gap. Anyone can publish on the changes key: a seq the store's log does not
        # hold must not move `last_seq`, or every later real change would look old.
        # So the log, not this message, says what happened up to it.
        changes = self.behind(seq, fetch)
        if self.last_seq < seq:
            log.warning(
                "change %d is not in the store's log: skipped (delivered up to %d); "
                "if real, the store's heartbeat brings it back",
                seq,
                self.last_seq,
            )
        return changes

    def behind(self, seq: int, fetch: Fetch) -> list[Change]:
        """Return what the store's log holds after `last_seq`, up to `seq` at most."""
        if seq <= self.last_seq:
            return []
        try:
            missed, _now = fetch(self.last_seq + 1, seq)
        except SpaceError as exc:
            log.warning("could not fetch changes %d..%d: %s", self.last_seq + 1, seq, exc)
            return []
        changes = []
        for payload in missed:
            try:
                got, cs = self.decode(payload)
            except MalformedPayload as exc:
                log.warning("malformed logged change skipped: %s", exc)
                continue
            if got > self.last_seq:
                changes += self._advance(got, cs)
        return changes

    def _advance(self, seq: int, cs: Changeset | None) -> list[Change]:
        self.last_seq = seq
        change = None if cs is None else self.filter(cs)
        return [] if change is None else [change]

    def filter(self, cs: Changeset) -> Change | None:
        """Return the matching part of a changeset, or None if nothing matches."""
        t = self.template
        if t.s is None and t.p is None and t.o is None:  # everything matches, nothing binds
            if isinstance(cs, Change):  # made for this subscription alone: delivered as it is
                return None if cs.is_empty() else cs
            lists = [cs.added, cs.removed, cs.inferred_added, cs.inferred_removed]
            bindings: list = []
        else:
            lists = [
                [x for x in triples if t.match(x) is not None]
                for triples in (cs.added, cs.removed, cs.inferred_added, cs.inferred_removed)
            ]
            bindings = [b for x in (y for ys in lists for y in ys) if (b := t.match(x))]
        if not any(lists):
            return None
        return Change(
            id=cs.id,
            agent=cs.agent,
            timestamp=cs.timestamp,
            cause=cs.cause,
            seq=cs.seq,
            prefixes=cs.prefixes,
            added=lists[0],
            removed=lists[1],
            inferred_added=lists[2],
            inferred_removed=lists[3],
            bindings=bindings,
            texts=cs.texts,
        )


# (first, last) -> (the logged payloads first..last still kept, the store's seq now)
Fetch = Callable[[int, int], tuple[list[bytes], int]]
LATEST = 2**62  # "up to the store's current sequence number" in a log request
