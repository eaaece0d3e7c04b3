"""Request/reply with the store over `Session.get`."""

from __future__ import annotations

import zenoh

from space.changeset import unpack
from space.errors import ChangesetRejected, QueryError, SpaceUnavailable


def ask_store(
    session: zenoh.Session, key: str, payload: bytes, timeout: float, *, what: str = "request"
) -> dict:
    """Send one request to the store's queryable and return its decoded reply.

    Blocks up to `timeout` seconds; call it from a normal thread, never from a
    Zenoh callback.

    Raises:
        SpaceUnavailable: no store answered in time.
        QueryError: the store answered with an error (bad SPARQL, malformed request).
    """
    replies = session.get(
        key,
        payload=payload,
        timeout=timeout,
        consolidation=zenoh.ConsolidationMode.NONE,
        congestion_control=zenoh.CongestionControl.BLOCK,
    )
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
