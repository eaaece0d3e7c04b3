"""A subscription to some (subject, predicate) pairs only: Zenoh filters, the chain finds gaps.

It declares one Zenoh subscriber per selector on `@/changes/<s>/<p1>/...` (see
`space._parts`: a part is a subject's triples, its predicates in its key) and
delivers the parts it receives as `Change`s, with the triples of the pairs it
selects only: the parts of
one changeset that arrive together (the store publishes them in one burst) as
one, a part that comes late as another with the same id and seq. After a part of
a changeset of many (`n` >= `BURST` pairs) the dispatcher waits for that changeset's
end, which the store publishes after its parts (`keys.end_key`): see `on_end`.
Per pair, it
remembers the seq of the last part delivered; the store's `prev` says which
seq it should be. When `prev` names one it never saw
(past `last_seq`, up to which it holds everything selected), it fetches the
log since `last_seq`, keeps the selected parts not delivered yet, and only
then delivers the part that showed the gap. A part lost with no later part on
its key comes back when its session reconnects or the leading store's token
comes back (a cut anywhere between them drops it): both fetch the log to now.
The heartbeat does not (it says the space moved, not whether its keys did).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from dataclasses import dataclass

import zenoh

from space import keys
from space._dispatch import Dispatcher
from space._parts import BURST, Part, PartKey, joined, only, split, term_chunk
from space._scope import Matcher, exact, patterns, selector_key, through
from space._subscription import LATEST, Callback, Change, Fetch, Subscription
from space.changeset import published_seq, unpack
from space.errors import MalformedPayload, SpaceError
from space.template import Template
from space.terms import Triple

log = logging.getLogger("tspace.subscription")

SLACK = 1_000_000  # a live part this far past the store's last known seq is checked in the log


class ScopedSubscription(Subscription):
    """One `subscribe(..., scope=...)`: the parts of changes on the selected keys.

    Args:
        selectors: `<s>/<p>`, each two chunks of key expressions (`selectors()` makes
            them from terms and IRI prefixes); `selector_key` makes their keys.
    """

    merges = True

    def __init__(
        self,
        dispatcher: Dispatcher,
        template: Template,
        callback: Callback,
        *,
        space: str,
        selectors: list[str],
        skip_agent: str | None = None,
    ) -> None:
        super().__init__(dispatcher, template, callback, skip_agent=skip_agent)
        self.space = space
        self.keys = [selector_key(space, s) for s in selectors]
        self.horizon = 0  # the highest seq the store itself said it reached
        self._last: dict[PartKey, int] = {}  # pair -> seq of the last part delivered on it
        self._patterns = [patterns(s) for s in selectors]  # (subject, predicate) chunk matchers
        self._exact = [exact(s) for s in selectors]  # their chunks without wildcards, or None
        self._choice: dict[PartKey, bool] = {}  # pair -> selected (`_chosen`)
        self._prefix = keys.service_key(space, "changes") + "/"
        self._token = os.urandom(8)  # marks this subscription's own samples of ends
        self._through = through(self.keys)  # one per selector, or none
        self._open: set[int] = set()  # changesets of many parts whose end has not come back
        self._ends: dict[int, int] = {}  # seq -> samples of its end come back so far

    @property
    def waiting(self) -> bool:  # type: ignore[override]
        """Whether parts received belong to a changeset of many whose end has not come."""
        return bool(self._open)

    def delivered(self) -> None:
        """Forget the changesets waited for: their parts went out (the end was late or lost)."""
        self._open.clear()

    def item(self, sample: zenoh.Sample) -> object:
        """Queue the part with its key (the chain is per key), or the end come back."""
        attachment = sample.attachment
        if attachment is None:
            return str(sample.key_expr), sample.payload.to_bytes()
        if attachment.to_bytes() != self._token:
            return None  # another subscription's end, or not the store's part
        seq, expected = sample.payload.to_bytes().split()
        return Ended(int(seq), int(expected))

    def on_end(self, session: zenoh.Session) -> Callable[[zenoh.Sample], None]:
        """Return the callback of the ends of changesets (`keys.end_key`).

        Zenoh hands this subscriber the end of a changeset after every part before
        it, but each of our part subscribers passes its samples on from a thread of
        its own, which may lag. So the end is sent back through each of them that
        may have received a part of it (`_echoes`), as a sample only this session
        hears on a key it selects, with how many samples of it are coming back:
        when all have (`receive`), every part of that changeset queued before them.
        """
        local = zenoh.Locality.SESSION_LOCAL

        def callback(sample: zenoh.Sample) -> None:
            try:
                end = unpack(sample.payload.to_bytes())
                seq = end["seq"]  # type: ignore[index]
            except (MalformedPayload, TypeError, KeyError) as exc:
                log.warning("malformed end of changeset skipped: %s", exc)
                return
            if not isinstance(seq, int) or isinstance(seq, bool):
                log.warning("end of changeset with a seq not an integer skipped: %r", seq)
                return
            echoes = self._echoes(end)  # type: ignore[arg-type]
            payload = f"{seq} {sum(n for _key, n in echoes)}"
            try:
                for key, _n in echoes:
                    session.put(key, payload, attachment=self._token, allowed_destination=local)
            except zenoh.ZError as exc:  # the session closing: nothing waits any more
                log.debug("end of changeset %d not sent back: %s", seq, exc)

        return callback

    def selects(self, triple: Triple) -> bool:
        """Return True for a triple whose (subject, predicate) key this subscription selects."""
        try:
            s, p = term_chunk(triple[0]), term_chunk(triple[1])
        except TypeError:
            return False
        return self._chosen(s, p)

    def _chosen(self, s: str, p: str) -> bool:
        """Return whether a selector selects the pair of chunks (s, p) (remembered)."""
        chosen = self._choice.get((s, p))
        if chosen is None:
            if len(self._choice) >= _CHOICES:
                self._choice.clear()
            chosen = any(bool(ms(s)) and bool(mp(p)) for ms, mp in self._patterns)
            self._choice[(s, p)] = chosen
        return chosen

    def start(self, seq: int) -> None:
        """Note the store's seq the subscription starts from."""
        self.horizon = max(self.horizon, seq)

    def merge(self, into: object, item: object) -> bool:
        """Fold parts of one changeset received together into one delivery."""
        if not (isinstance(into, Received) and isinstance(item, Received)):
            return False
        if into.seq != item.seq or into.id != item.id:
            return False
        into.parts += item.parts
        return True

    def change(self, item: object) -> Change | None:
        """Parse the parts of one delivery at once (a part with a malformed term is left out)."""
        if not isinstance(item, Received):
            return item  # type: ignore[return-value]  # the snapshot, parsed already
        try:
            return self._parsed(joined(item.parts))
        except MalformedPayload:
            good = [part for part in item.parts if self._parses(part)]
            return self._parsed(joined(good)) if good else None

    def _parsed(self, wire: Part) -> Change | None:
        return self.filter(Change.from_wire(wire, published=True))

    @staticmethod
    def _parses(part: Part) -> bool:
        try:
            Change.from_wire(part, published=True)
        except MalformedPayload as exc:
            log.warning("malformed change skipped: %s", exc)
            return False
        return True

    def _echoes(self, end: dict) -> list[tuple[str, int]]:
        """Return the keys to send an end back on (`through`): its selectors' that may match.

        A part reaches the subscriber of a key expression only if its subject matches
        the selector's subject and one of its predicates the selector's predicate; the
        end names its changeset's subjects and predicates (each list when short): a
        selector that matches none of either received no part of it. Empty: no part was
        ours, nothing waits for this end.
        """
        subjects, predicates = _Named.of(end, "s"), _Named.of(end, "p")
        return [
            through
            for through, (ms, mp), (es, ep) in zip(
                self._through, self._patterns, self._exact, strict=False
            )
            if subjects.hit(ms, es) and predicates.hit(mp, ep)
        ]

    def receive(self, item: object, fetch: Fetch) -> list[Received]:
        """Return what to deliver for a received part, the missed parts first.

        Raises:
            MalformedPayload: not a published part (no id, seq or `prev`).
        """
        if isinstance(item, Ended):
            self._ended(item.seq, item.expected)
            return []
        key, payload = item  # type: ignore[misc]
        wire = unpack(payload)
        seq = published_seq(wire)
        assert isinstance(wire, dict)
        s, predicates = self._pairs(key)
        prevs = _prevs(wire.get("prev"), len(predicates), seq)
        count = wire.get("n")  # optional: how many pairs its changeset has
        fresh: list[str] = []  # the part's selected predicates not delivered yet
        gap = False
        for p, prev in zip(predicates, prevs, strict=True):
            known = max(self.last_seq, self._last.get((s, p), 0))
            if seq > known and self._chosen(s, p):
                fresh.append(p)
                gap = gap or prev > known
        if not fresh:
            return []
        if len(fresh) < len(predicates):
            wire = only(wire, set(fresh))  # checks their triples: a bad one skips the part
        changes: list[Received] = []
        if gap or seq > self.horizon + SLACK:
            try:
                changes = self._fetch(seq - 1, fetch)
            except SpaceError as exc:
                log.warning("part %d on %s held back, the log is out of reach: %s", seq, key, exc)
                return []
            if seq > self.horizon:
                log.warning(
                    "part %d on %s is past the store's seq %d: skipped", seq, key, self.horizon
                )
                return changes
        for p in fresh:
            self._last[(s, p)] = seq
        received = self._changes(wire)
        if received and isinstance(count, int) and count >= BURST:
            self._open.add(seq)  # more may come: delivery waits for its end
        return changes + received

    def _pairs(self, key: str) -> tuple[str, list[str]]:
        """Return the subject chunk and the predicate chunks of a part's key.

        Raises:
            MalformedPayload: not a part's key of this space.
        """
        chunks_ = key[len(self._prefix) :].split("/") if key.startswith(self._prefix) else []
        if len(chunks_) < 2:
            raise MalformedPayload(f"not a part's key: {key:.120}")
        return chunks_[0], chunks_[1:]

    def _ended(self, seq: int, expected: int) -> None:
        """Count a sample of a changeset's end come back; the `expected`th ends the wait for it."""
        back = self._ends.get(seq, 0) + 1
        if back < expected:
            if len(self._ends) > _ENDS:  # ends never completed (a subscriber closed, a cut)
                self._ends.clear()
            self._ends[seq] = back
            return
        self._ends.pop(seq, None)
        self._open.discard(seq)

    def behind(self, seq: int, fetch: Fetch) -> list[Received]:
        """Fetch the log to now on a reconnection or a new leader (`LATEST`); ignore heartbeats.

        An end is lost only with its link or its store (Zenoh drops nothing on a link
        that holds; ends and parts block rather than drop): what waited for one is
        delivered now.
        """
        if seq != LATEST:
            return []
        self._open.clear()
        try:
            return self._fetch(LATEST, fetch)
        except SpaceError as exc:
            log.warning("could not fetch changes after %d: %s", self.last_seq, exc)
            return []

    def _fetch(self, last: int, fetch: Fetch) -> list[Received]:
        """Deliver the selected parts logged after `last_seq`, up to `last`, not delivered yet.

        Raises:
            SpaceError: the log did not answer.
        """
        if last <= self.last_seq:
            return []
        payloads, now = fetch(self.last_seq + 1, last)
        self.horizon = max(self.horizon, now)
        changes: list[Received] = []
        for payload in payloads:
            try:
                wire = unpack(payload)
                seq = published_seq(wire)
                assert isinstance(wire, dict)
                if seq <= self.last_seq:
                    continue
                parts = split(wire)
            except MalformedPayload as exc:
                log.warning("malformed logged change skipped: %s", exc)
                continue
            kept = self._kept(parts, seq)
            if kept is not None:
                changes += self._changes(kept)
        self.last_seq = max(self.last_seq, min(last, now))
        return changes

    def _kept(self, parts: dict[tuple[str, str], Part], seq: int) -> Part | None:
        """Return the selected parts of one logged changeset not delivered yet, merged."""
        kept = []
        for (s, p), part in parts.items():
            if seq <= self._last.get((s, p), 0) or not self._chosen(s, p):
                continue
            self._last[(s, p)] = seq
            kept.append(part)
        return joined(kept) if kept else None

    def _changes(self, wire: Part) -> list[Received]:
        if self.skip_agent is not None and wire.get("agent") == self.skip_agent:
            return []
        return [Received(wire["seq"], wire["id"], [wire])]


@dataclass(frozen=True)
class Ended:
    """The end of a changeset, come back through one of a subscription's part subscribers."""

    seq: int
    expected: int  # how many samples of it come back in all


_ENDS = 64  # changesets whose end is partly back, at most (more: the oldest were lost)
_CHOICES = 100_000  # pairs whose selection is remembered, at most (then forgotten at once)


class _Named:
    """The chunks an end names in one of its lists (None: it does not name them all)."""

    def __init__(self, chunks: list[str] | None) -> None:
        self.chunks = chunks
        self._set: set[str] | None = None

    @classmethod
    def of(cls, end: dict, name: str) -> _Named:
        listed = end.get(name)
        if isinstance(listed, list) and all(isinstance(x, str) for x in listed):
            return cls(listed)
        return cls(None)

    def hit(self, matcher: Matcher, exact: str | None) -> bool:
        """Return whether a selector's chunk (its `matcher`, or `exact`) matches one named.

        An exact chunk is looked up (a 200-predicate end against 4 shared predicates:
        100 us of regular expressions per end, for every robot's agents, else).
        """
        if self.chunks is None:
            return True
        if exact is None:
            return any(map(matcher, self.chunks))
        if self._set is None:
            self._set = set(self.chunks)
        return exact in self._set


def _prevs(prev: object, count: int, seq: int) -> list[int]:
    """Return a part's `prev` for each of its `count` pairs (one pair: an int, else a list).

    Raises:
        MalformedPayload: not that, or a `prev` not below the part's seq.
    """
    prevs = [prev] if count == 1 else prev
    if (
        not isinstance(prevs, list)
        or len(prevs) != count
        or not all(isinstance(x, int) and not isinstance(x, bool) and 0 <= x < seq for x in prevs)
    ):
        raise MalformedPayload(
            f"a published part has a 'prev' below its seq for each pair, got {prev!r:.80}"
        )
    return prevs  # type: ignore[return-value]


@dataclass
class Received:
    """Parts of one changeset received together: their terms are parsed once, when delivered."""

    seq: int
    id: str
    parts: list[Part]
