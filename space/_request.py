"""Request/reply with the store: over declared Zenoh queriers, or `Session.get`."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from typing import TypeVar

import zenoh

from space.changeset import unpack
from space.errors import (
    ChangesetRejected,
    NoQuorum,
    QueryError,
    QueryTimeLimit,
    SpaceTimeout,
    SpaceUnavailable,
)

K = TypeVar("K")
E = TypeVar("E", zenoh.Querier, zenoh.Publisher)


class Queriers:
    """A handle's declared queriers, one per (key, timeout) it asks the store on, and
    its declared publishers (fire-and-forget writes).

    Zenoh means repeated queries on one key to go through a `Querier` declared
    once (the key resolved and routed once, not per request), and repeated puts
    through a `Publisher`. The timeout is a querier's own, so a request whose
    timeout has no querier yet declares one, up to `LIMIT`; past that (a caller
    inventing timeouts) it is a plain GET.
    """

    LIMIT = 16

    def __init__(self, session: zenoh.Session) -> None:
        self.session = session
        self._queriers: dict[tuple[str, float], zenoh.Querier] = {}
        self._publishers: dict[str, zenoh.Publisher] = {}
        self._lock = threading.Lock()
        self._closed = False

    def put(self, key: str, payload: bytes) -> None:
        """Publish one fire-and-forget request on `key` (blocking while congested)."""
        publisher = self._declared(
            self._publishers,
            key,
            lambda: self.session.declare_publisher(
                key, congestion_control=zenoh.CongestionControl.BLOCK
            ),
        )
        if publisher is None:
            self.session.put(key, payload, congestion_control=zenoh.CongestionControl.BLOCK)
        else:
            publisher.put(payload)

    def get(self, key: str, payload: bytes, timeout: float) -> zenoh.Handler:
        """Send one request; return the handler its replies come in on."""
        querier = self._declared(
            self._queriers,
            (key, timeout),
            lambda: self.session.declare_querier(
                key,
                timeout=timeout,
                consolidation=zenoh.ConsolidationMode.NONE,
                congestion_control=zenoh.CongestionControl.BLOCK,
            ),
        )
        if querier is None:
            return _get(self.session, key, payload, timeout)
        return querier.get(payload=payload)

    def close(self) -> None:
        """Undeclare everything (before the session closes); later requests are plain ones."""
        with self._lock:
            declared = [*self._queriers.values(), *self._publishers.values()]
            self._queriers, self._publishers, self._closed = {}, {}, True
        for entity in declared:
            entity.undeclare()

    def _declared(self, table: dict[K, E], key: K, declare: Callable[[], E]) -> E | None:
        """Return `table`'s entity for `key`, declaring it if there is room (None: ask plainly)."""
        with self._lock:
            entity = table.get(key)
            if entity is None and len(table) < self.LIMIT and not self._closed:
                entity = table[key] = declare()
            return entity


Asker = zenoh.Session | Queriers  # what a request goes out through


def ask_store(
    session: Asker, key: str, payload: bytes, timeout: float, *, what: str = "request"
) -> dict:
    """Send one request to the store's queryable and return its decoded reply.

    Blocks up to `timeout` seconds; call it from a normal thread, never from a
    Zenoh callback. While no store is reachable at all (a router reconnecting,
    a replica taking over) the request is sent again until the timeout.

    Raises:
        SpaceUnavailable: no store was reachable in time.
        SpaceTimeout: a store was reached but did not answer in time (a write
            may still be applied).
        QueryError: the store answered with an error (bad SPARQL, malformed request).
        QueryTimeLimit: the read ran past its time limit at the store.
        ChangesetRejected: the store refused a write (`what="write"`).
    """
    deadline = time.monotonic() + timeout
    replies = list(_send(session, key, payload, timeout))
    while not replies and deadline - time.monotonic() >= 0.05:
        time.sleep(0.05)  # nobody answered at once: no queryable reachable yet
        replies = list(_get(_plain(session), key, payload, deadline - time.monotonic()))
    return _decode(replies, key, timeout, what)


class Pending:
    """A request sent to the store whose reply is read later: `ask_store`'s non-blocking twin.

    Constructing it sends the request and returns at once; `result()` blocks for
    the reply, `ready()` tells without blocking whether the request ended. Requests from
    one session reach the store in the order they were sent, so a caller may send
    several before reading their replies (pipelining).
    A request that found no store at all is sent again by `result()`, until its
    timeout, as `ask_store` does: after any sent since.
    """

    def __init__(
        self, session: Asker, key: str, payload: bytes, timeout: float, *, what: str
    ) -> None:
        self._session, self._key, self._payload, self._what = session, key, payload, what
        self._timeout = timeout
        self._deadline = time.monotonic() + timeout
        self._replies = _send(session, key, payload, timeout)
        self._got: list[zenoh.Reply] = []
        self._ended = False

    def ready(self) -> bool:
        """Return whether the request ended (answered, refused or timed out), without waiting."""
        while not self._ended:
            try:
                reply = self._replies.try_recv()
            except zenoh.ZError:  # the channel is closed: every reply is in
                self._ended = True
                break
            if reply is None:
                return False
            self._got.append(reply)
        return True

    def result(self) -> dict:
        """Wait for the reply and return it decoded.

        Raises:
            SpaceUnavailable, SpaceTimeout, QueryError, ChangesetRejected: as `ask_store`.
        """
        replies = self._got if self._ended else [*self._got, *self._replies]
        left = self._deadline - time.monotonic()
        if not replies and left >= 0.05:
            plain = _plain(self._session)  # a timeout of its own: no querier declared for it
            return ask_store(plain, self._key, self._payload, left, what=self._what)
        return _decode(replies, self._key, self._timeout, self._what)


def _plain(asker: Asker) -> zenoh.Session:
    return asker.session if isinstance(asker, Queriers) else asker


def _send(asker: Asker, key: str, payload: bytes, timeout: float) -> zenoh.Handler:
    """Send a request the caller's way: on a declared querier if it has them."""
    if isinstance(asker, Queriers):
        return asker.get(key, payload, timeout)
    return _get(asker, key, payload, timeout)


def _get(session: zenoh.Session, key: str, payload: bytes, timeout: float) -> zenoh.Handler:
    return session.get(
        key,
        payload=payload,
        timeout=max(timeout, 0.001),
        consolidation=zenoh.ConsolidationMode.NONE,
        congestion_control=zenoh.CongestionControl.BLOCK,
    )


# The error reply Zenoh itself makes when a queryable was reached but did not answer in
# time; the store's own error replies are sentences, never this one word.
_ZENOH_TIMEOUT = "Timeout"
TIME_LIMIT = "time limit: "
# A cluster replica on a minority side refuses with NoQuorum's sentence (space.errors).
_NO_QUORUM = re.compile(
    r"no quorum: (\d+) of (\d+) members reachable(?: \((.*)\))?$"
)  # how the store's error reply to a read past its time limit starts


def _decode(replies: list[zenoh.Reply], key: str, timeout: float, what: str) -> dict:
    errors = []
    for reply in replies:
        if reply.ok is not None:
            value = unpack(reply.ok.payload.to_bytes())
            if not isinstance(value, dict):
                raise QueryError(f"unexpected reply to {what}: {value!r}")
            return value
        errors.append(reply.err.payload.to_string() if reply.err is not None else "unknown error")
    refusals = [message for message in errors if message != _ZENOH_TIMEOUT]
    if refusals and refusals[0].startswith(TIME_LIMIT):
        raise QueryTimeLimit(refusals[0][len(TIME_LIMIT) :])
    quorum = _NO_QUORUM.match(refusals[0]) if refusals else None
    if quorum:
        raise NoQuorum(int(quorum[1]), int(quorum[2]), quorum[3] or "")
    if refusals:
        raise (ChangesetRejected if what == "write" else QueryError)(refusals[0])
    if errors:
        late = " (the changeset may still be applied)" if what == "write" else ""
        raise SpaceTimeout(f"no answer from the store to the {what} within {timeout:g} s{late}")
    raise SpaceUnavailable(f"no store answered the {what} on {key} within {timeout:g} s")
