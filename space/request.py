"""Request/reply with the store over `Session.get`."""

from __future__ import annotations

import time

import zenoh

from space.changeset import unpack
from space.errors import ChangesetRejected, QueryError, SpaceUnavailable


def ask_store(
    session: zenoh.Session, key: str, payload: bytes, timeout: float, *, what: str = "request"
) -> dict:
    """Send one request to the store's queryable and return its decoded reply.

    Blocks up to `timeout` seconds; call it from a normal thread, never from a
    Zenoh callback. While no store is reachable at all (a router reconnecting,
    a replica taking over) the request is sent again until the timeout.

    Raises:
        SpaceUnavailable: no store answered in time.
        QueryError: the store answered with an error (bad SPARQL, malformed request).
    """
    deadline = time.monotonic() + timeout
    while True:
        left = deadline - time.monotonic()
        replies = list(
            session.get(
                key,
                payload=payload,
                timeout=max(left, 0.001),
                consolidation=zenoh.ConsolidationMode.NONE,
                congestion_control=zenoh.CongestionControl.BLOCK,
            )
        )
        if replies or deadline - time.monotonic() < 0.05:
            break
        time.sleep(0.05)  # nobody answered at once: no queryable reachable yet
    for reply in replies:
        if reply.ok is not None:
            value = unpack(reply.ok.payload.to_bytes())
            if not isinstance(value, dict):
                raise QueryError(f"unexpected reply to {what}: {value!r}")
            return value
        message = reply.err.payload.to_string() if reply.err is not None else "unknown error"
        if what == "write":
            raise ChangesetRejected(message)
        raise QueryError(message)
    raise SpaceUnavailable(f"no store answered the {what} on {key} within {timeout:g} s")
