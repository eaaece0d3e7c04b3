"""Reading a space: template reads, take, SPARQL, the log and `why` (see `TripleSpace`)."""

from __future__ import annotations

import io
import uuid

from rdflib import Graph
from rdflib.query import Result

from space import keys
from space._handle import Handle, TemplateLike, _triples
from space._request import ask_store
from space.changeset import Changeset, pack
from space.errors import MalformedPayload, NoReasoner, QueryError, SpaceTimeout, SpaceUnavailable
from space.explanation import Explanation
from space.terms import Triple, triple_from_nt


class Reads(Handle):
    """The read operations of `TripleSpace`."""

    def read(self, template: TemplateLike = None, *, timeout: float = 5.0) -> Graph:
        """Return the matching triples of one subject (the first in IRI order)."""
        t = self._template(template)
        return self._graph(self._ask({"op": "read", "template": t.to_wire()}, timeout))

    def query(
        self,
        template: TemplateLike = None,
        *,
        graph: str = "all",
        timeout: float = 5.0,
        stale: bool | None = None,
    ) -> Graph:
        """Return every matching triple of the asserted, inferred or `all` graphs.

        `stale` (default: the handle's `stale`): in cluster mode, answer from
        the nearest replica even where no quorum is reachable (possibly behind)
        instead of raising `NoQuorum`.
        """
        t = self._template(template)
        request = {"op": "query", "template": t.to_wire(), "graph": graph}
        return self._graph(self._ask(request, timeout, stale))

    def match(
        self, template: TemplateLike = None, *, graph: str = "all", timeout: float = 5.0
    ) -> list[Triple]:
        """Return the matching triples as a list: `query` without building a Graph (faster)."""
        t = self._template(template)
        reply = self._ask({"op": "query", "template": t.to_wire(), "graph": graph}, timeout)
        return list(dict.fromkeys(_triples(reply)))

    def lifespans(
        self, template: TemplateLike = None, *, timeout: float = 5.0
    ) -> list[tuple[Triple, float | None]]:
        """Return each matching asserted triple with the seconds it has left (None: permanent)."""
        t = self._template(template)
        request = {"op": "query", "template": t.to_wire(), "graph": "asserted", "lifespan": True}
        reply = self._ask(request, timeout)
        rows = reply.get(keys.ASSERTED) or []
        left = reply.get("lifespan") or [None] * len(rows)
        if not isinstance(left, list) or len(left) != len(rows):
            raise MalformedPayload("a lifespan reply has one remaining life per triple")
        return [(triple_from_nt(r), life) for r, life in zip(rows, left, strict=True)]

    def take(self, template: TemplateLike = None, *, timeout: float = 5.0) -> Graph:
        """Remove every matching asserted triple and return them, atomically at the store.

        The request carries an id: sent again while no store answers (a restart),
        it gets the first outcome, never a second take.
        """
        t = self._template(template)
        request = {
            "op": "take",
            "id": uuid.uuid4().hex,
            "template": t.to_wire(),
            "agent": self.agent,
            "ts": str(self.session.new_timestamp()),
        }
        return self._graph(self._ask(request, timeout))

    def snapshot(self, template: TemplateLike = None, *, timeout: float = 5.0) -> tuple[Graph, int]:
        """Return the matching state (both graphs) and the sequence number it reflects."""
        reply = self._snapshot(self._template(template), timeout)
        return self._graph(reply), int(reply.get("seq") or 0)

    def graphs(
        self, template: TemplateLike = None, *, timeout: float = 5.0
    ) -> tuple[list[Triple], list[Triple], int]:
        """Return the matching asserted and inferred triples, apart, from one read.

        Also returns the sequence number that read reflects: a subscriber that
        subscribed first knows which of the changes it receives the read holds.
        """
        reply = self._snapshot(self._template(template), timeout)
        asserted = [triple_from_nt(x) for x in reply.get(keys.ASSERTED) or ()]
        inferred = [triple_from_nt(x) for x in reply.get(keys.INFERRED) or ()]
        return asserted, inferred, int(reply.get("seq") or 0)

    def query_sparql(self, text: str, *, timeout: float = 5.0) -> Result:
        """Run a SPARQL SELECT, ASK or CONSTRUCT over the union of both graphs.

        Raises:
            QueryError: the store rejected the query.
            QueryTimeLimit: it ran past `timeout` (or the store's `--query-timeout`).
        """
        reply = self._ask({"op": "sparql", "text": text}, timeout)
        body = reply.get("body") or b""
        if reply.get("type") in ("CONSTRUCT", "DESCRIBE"):
            result = Result(reply["type"])
            result.graph = Graph().parse(data=body, format="nt")
            return result
        try:
            return Result.parse(io.BytesIO(body), format="json")
        except ValueError as exc:
            raise QueryError(f"unreadable SPARQL result: {exc}") from exc

    def seq(self, *, timeout: float = 5.0) -> int:
        """Return the space's sequence number now (how many changesets it has applied).

        Raises:
            SpaceUnavailable, SpaceTimeout: as `query`.
        """
        return self._seq(timeout)

    def history(
        self, first: int = 1, last: int = 0, *, timeout: float = 5.0
    ) -> tuple[list[Changeset], int]:
        """Return the changesets `first..last` the store's log still keeps, oldest first.

        `last` 0 means up to the newest. Also returns the space's sequence number
        now. The store keeps a bounded log (`tspace serve --log-keep`): older
        changesets are gone and simply missing from the answer.

        Raises:
            SpaceUnavailable, SpaceTimeout: as `query`.
            MalformedPayload: the store sent a changeset that cannot be read.
        """
        request = {"from": max(1, first)}
        if last:
            request["to"] = last
        key = self._key("log")
        reply = ask_store(self._queriers, key, pack(request), timeout, what="log request")
        changes = [Changeset.decode(bytes(p), published=True) for p in reply.get("changes") or ()]
        return changes, int(reply.get("seq") or 0)

    def why(
        self, template: TemplateLike = None, *, limit: int = 20, timeout: float = 5.0
    ) -> list[Explanation]:
        """Return why each triple matching `template` holds (at most `limit` of them).

        The space's reasoner answers (on `@/why`, see docs/wire-format.md): for
        each matching triple, the rule that concluded it with the comment above
        the rule in its file, the facts the rule matched, explained in turn, down
        to what agents wrote, with who wrote it and when. A triple that does not
        hold has no explanation: no match gives an empty list.

        Raises:
            NoReasoner: no reasoner answered within `timeout`.
            QueryError: the reasoner refused the request.
        """
        t = self._template(template)
        request = {"template": t.to_wire(), "limit": int(limit)}
        try:
            reply = ask_store(self._queriers, self._key("why"), pack(request), timeout, what="why")
        except (SpaceUnavailable, SpaceTimeout) as exc:
            raise NoReasoner(
                f"no reasoner answered on space {self.space!r} within {timeout:g} s "
                "(is one running? `tspace up` starts one)"
            ) from exc
        found = reply.get("explanations") or []
        if not isinstance(found, list):
            raise MalformedPayload("the reasoner's 'explanations' is not a list")
        return [Explanation.from_wire(w) for w in found]
