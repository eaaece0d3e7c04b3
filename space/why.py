"""Serve `why` on a space: the `<root>/<space>/@/why` queryable a reasoner declares.

The queryable's callback only queues the query (nothing blocks in Zenoh); the
owner's thread calls `answer_pending` with a function that explains what a
template matches (a reasoner's engine is not thread-safe). The request and
reply shapes are in docs/wire-format.md; `TripleSpace.why` is the other end.
"""

from __future__ import annotations

import logging
import queue
from collections.abc import Callable

import zenoh

from space.changeset import pack, unpack
from space.errors import MalformedPayload, SpaceError
from space.explanation import Explanation
from space.keys import service_key
from space.template import Template
from space.terms import from_nt

log = logging.getLogger("tspace.why")

LIMIT = 100  # triples explained per request, at most

Explain = Callable[[Template, int], tuple[list[Explanation], bool]]


class WhyService:
    """The `@/why` queryable of one space; its queries wait for `answer_pending`."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[zenoh.Query] = queue.SimpleQueue()
        self._queryable: zenoh.Queryable | None = None

    def open(self, session: zenoh.Session, space: str) -> None:
        """Declare the queryable (once)."""
        if self._queryable is None:
            self._queryable = session.declare_queryable(service_key(space, "why"), self._queue.put)

    def close(self) -> None:
        """Undeclare the queryable; queued queries are dropped unanswered."""
        if self._queryable is not None:
            self._queryable.undeclare()
            self._queryable = None

    def answer_pending(self, explain: Explain) -> None:
        """Answer every queued query on the caller's thread.

        `explain(template, limit)` returns the explanations of at most `limit`
        matching triples and whether more matched. A malformed request gets an
        error reply naming what is wrong; the owner goes on.
        """
        while True:
            try:
                query = self._queue.get_nowait()
            except queue.Empty:
                return
            key = str(query.key_expr)
            try:
                payload = query.payload.to_bytes() if query.payload is not None else b""
                template, limit = _request(unpack(payload))
                trees, more = explain(template, limit)
                reply = {"explanations": [tree.to_wire() for tree in trees], "more": more}
                query.reply(key, pack(reply))
            except (SpaceError, ValueError) as exc:
                log.warning("why request refused: %s", exc)
                query.reply_err(f"why: {exc}".encode())
            finally:
                query.drop()


def _request(request: object) -> tuple[Template, int]:
    """Return the template and limit of a why request.

    Raises:
        MalformedPayload: not `{template: [s, p, o] or null, limit: n}`.
    """
    if not isinstance(request, dict):
        raise MalformedPayload("a why request is a map {template, limit}")
    wire = request.get("template")
    if wire is not None and (not isinstance(wire, list | tuple) or len(wire) != 3):
        raise MalformedPayload(f"a template is three terms or nulls, got {wire!r}")
    template = Template(*(None if t is None else from_nt(t) for t in (wire or (None,) * 3)))
    try:
        limit = int(request.get("limit") or 20)
    except (TypeError, ValueError) as exc:
        raise MalformedPayload(f"a why limit is a number, got {request.get('limit')!r}") from exc
    return template, max(1, min(limit, LIMIT))
