"""TripleSpace: the Triple Space Computing operations over a Zenoh session.

After otsopack/TripCom: `write`, `read`, `query`, `take`, `subscribe`, each
with a timeout. Every blocking call waits for the store; none may be called
from inside a Zenoh callback (subscription callbacks run in the library's own
dispatcher thread, where they are fine).
"""

from __future__ import annotations

import io
import logging
import uuid
from collections.abc import Iterable, Iterator
from contextlib import ExitStack, contextmanager
from types import TracebackType
from typing import TYPE_CHECKING

import zenoh
from rdflib import Graph, URIRef
from rdflib.query import Result

from space import keys
from space._request import Pending, ask_store
from space._scoped import Scope, ScopedSubscription, selectors
from space._session import open_session
from space._subscription import Callback, Change, Dispatcher, Subscription
from space.ack import Ack
from space.changeset import Changeset, pack, unpack
from space.errors import (
    InputError,
    MalformedPayload,
    NoReasoner,
    QueryError,
    SpaceTimeout,
    SpaceUnavailable,
    TemplateError,
)
from space.explanation import Explanation
from space.lifespan import check_lifespan
from space.prefixes import PrefixMap
from space.template import Template
from space.terms import CACHED, Triple, triple_from_nt

if TYPE_CHECKING:
    from space.identity import Identity

log = logging.getLogger("tspace.client")

TemplateLike = Template | tuple | str | None
Triples = Iterable[Triple] | Graph


class TripleSpace:
    """A handle on one space, over a Zenoh session.

    Built on a session you own (`TripleSpace(session, ...)`), it leaves the
    session open on `close()`; `TripleSpace.open(...)` opens its own session
    and closes it. Either way, use it as a context manager.
    """

    def __init__(
        self,
        session: zenoh.Session,
        space: str = "default",
        *,
        agent: str | None = None,
        prefixes: dict[str, str] | None = None,
        strict: bool = False,
        writer: str | None = None,
        lifespan: float | None = None,
        _owns_session: bool = False,
    ) -> None:
        self.session = session
        self.strict = strict
        # In cluster mode a read is refused where no quorum is reachable (NoQuorum),
        # unless the caller accepts a possibly stale answer: per call or here.
        self.stale = False
        self.lifespan = check_lifespan(lifespan)  # the default of every write (None: permanent)
        self.space = keys.check_space(space)
        # In a secure space a router lets each identity write (and take) only on
        # keys that end with its own name, so the store knows who wrote.
        self.writer = writer
        self.agent = agent or f"client-{session.zid()}"
        self.prefixes = PrefixMap(prefixes)
        self._owns_session = _owns_session
        self._dispatcher = Dispatcher(self._fetch_log)
        self._subscriptions: set[Subscription] = set()
        self._watchdogs: list = []

    @classmethod
    def open(
        cls,
        connect: list[str] | str | None = None,
        *,
        space: str = "default",
        agent: str | None = None,
        config_file: str | None = None,
        mode: str = "client",
        prefixes: dict[str, str] | None = None,
        strict: bool = False,
        identity: Identity | None = None,
        lifespan: float | None = None,
    ) -> TripleSpace:
        """Open a session to the routers at `connect` and a handle on `space`.

        Blocks until a router is reached. `prefixes` (name -> namespace IRI) are
        used in templates and sent with the changesets that use them, so the
        space learns them too. With `strict`, a write some of whose triples the
        store did not apply raises `NotApplied` (see `send`). With `identity`
        (`space.load_identity`), every link is mutual TLS with its certificate,
        and writes go under its name.
        `lifespan`: the default lifespan in seconds of every write of this handle
        (see `write`).

        Raises:
            InputError: `space` is not a legal space name (checked before connecting).
            ConfigError: an endpoint or the configuration file is malformed.
            SpaceUnavailable: no router reachable.
        """
        keys.check_space(space)
        endpoints = [connect] if isinstance(connect, str) else connect
        session = open_session(endpoints, mode=mode, config_file=config_file, identity=identity)
        writer = identity.name if identity is not None else None
        try:
            return cls(
                session,
                space,
                agent=agent,
                prefixes=prefixes,
                strict=strict,
                writer=writer,
                lifespan=lifespan,
                _owns_session=True,
            )
        except BaseException:
            session.close()
            raise

    def close(self) -> None:
        """Undeclare every subscription and close the session if this handle opened it.

        Each step runs even when an earlier one raised (its error is re-raised after):
        a session left open keeps the process from exiting.
        """
        subscriptions, self._subscriptions = list(self._subscriptions), set()
        watchdogs, self._watchdogs = self._watchdogs, []
        with ExitStack() as steps:  # run in reverse: subscriptions first, the session last
            if self._owns_session:
                steps.callback(self.session.close)
            steps.callback(self._dispatcher.close)
            for watchdog in watchdogs:
                steps.callback(watchdog.undeclare)
            for sub in subscriptions:
                steps.callback(sub.close)

    def __enter__(self) -> TripleSpace:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def _key(self, service: str) -> str:
        key = keys.service_key(self.space, service)
        if self.writer is not None and service in ("write", "query"):
            return f"{key}/{self.writer}"
        return key

    # Writing

    def changeset(
        self,
        added: Triples = (),
        removed: Triples = (),
        *,
        inferred_added: Triples = (),
        inferred_removed: Triples = (),
        cause: str | None = None,
        lifespan: float | None = None,
    ) -> Changeset:
        """Build a stamped changeset (not yet sent) from triples or graphs.

        `lifespan`: seconds after which the store retracts the added triples
        that no later write asserted again (None: the handle's default; 0: permanent).
        """
        life = self.lifespan if lifespan is None else lifespan
        cs = Changeset(
            agent=self.agent,
            timestamp=str(self.session.new_timestamp()),
            cause=cause,
            lifespan=check_lifespan(life) or None,
            added=list(added),
            removed=list(removed),
            inferred_added=list(inferred_added),
            inferred_removed=list(inferred_removed),
        )
        cs.prefixes = _used_prefixes(cs, [added, removed], self.prefixes)
        return cs

    def send(self, cs: Changeset, *, timeout: float = 5.0, strict: bool | None = None) -> Ack:
        """Send a changeset and wait until the store has made it durable; return its ack.

        The ack is the changeset's id (a `str`) with `seq` and `dropped`: the added
        triples the store did not apply and why (a functional property holding a
        newer value). Sent again while no store answers (a restart, a failover),
        it is applied once: the store knows its id.

        Raises:
            NotApplied: `strict` (default: the handle's) and some triple was not applied.
            SpaceUnavailable: no store was reachable within `timeout`.
            SpaceTimeout: a store was reached but did not acknowledge within
                `timeout`; the changeset may still be applied.
            ChangesetRejected: the store refused it.
        """
        reply = ask_store(self.session, self._key("write"), cs.encode(), timeout, what="write")
        ack = Ack.of(cs.id, reply)
        return ack.check() if (self.strict if strict is None else strict) else ack

    def send_later(self, cs: Changeset, *, timeout: float = 5.0) -> Pending:
        """Send a changeset now and read the acknowledgement later (`send`'s pipelined twin).

        Returns at once; `result()` of what it returns blocks as `send` does and
        raises what `send` raises. Changesets sent one after the other are applied
        in that order, so a writer may keep several in flight.
        """
        return Pending(self.session, self._key("write"), cs.encode(), timeout, what="write")

    def send_rows_later(
        self,
        added: list[list[str]],
        *,
        prefixes: dict[str, str] | None = None,
        lifespan: float | None = None,
        timeout: float = 5.0,
    ) -> tuple[str, Pending]:
        """Send triples given as `[s, p, o]` N-Triples texts as one changeset; ack read later.

        The bulk twin of `send_later`, for texts a parser made already (`tspace
        write` of a big document): no rdflib term is made. `lifespan` as in
        `changeset`. Returns the changeset's id and its pending reply
        (`Ack.of(id, pending.result())`).
        """
        life = self.lifespan if lifespan is None else lifespan
        cs = Changeset(
            agent=self.agent,
            timestamp=str(self.session.new_timestamp()),
            prefixes=dict(prefixes or {}),
            lifespan=check_lifespan(life) or None,
        )
        payload = cs.encode([added, [], [], []])
        return cs.id, Pending(self.session, self._key("write"), payload, timeout, what="write")

    def send_nowait(self, cs: Changeset) -> str:
        """Send a changeset without waiting (fire-and-forget twin of `send`); return its id."""
        self.session.put(
            self._key("write"), cs.encode(), congestion_control=zenoh.CongestionControl.BLOCK
        )
        return cs.id

    def write(
        self,
        triples: Triples,
        *,
        timeout: float = 5.0,
        cause: str | None = None,
        strict: bool | None = None,
        lifespan: float | None = None,
    ) -> Ack:
        """Add triples as one changeset; block until durable; return the ack (see `send`).

        `lifespan`: seconds until the store retracts them, unless written again
        before (a write renews); None takes the handle's default, 0 is permanent.
        """
        cs = self.changeset(triples, cause=cause, lifespan=lifespan)
        return self.send(cs, timeout=timeout, strict=strict)

    def write_nowait(
        self, triples: Triples, *, cause: str | None = None, lifespan: float | None = None
    ) -> str:
        """Add triples without waiting for the store (for high-rate sensor data)."""
        return self.send_nowait(self.changeset(triples, cause=cause, lifespan=lifespan))

    def remove(self, triples: Triples, *, timeout: float = 5.0, cause: str | None = None) -> Ack:
        """Remove triples as one changeset; block until durable."""
        return self.send(self.changeset((), triples, cause=cause), timeout=timeout)

    def apply(
        self,
        added: Triples = (),
        removed: Triples = (),
        *,
        inferred_added: Triples = (),
        inferred_removed: Triples = (),
        cause: str | None = None,
        timeout: float = 5.0,
        strict: bool | None = None,
        lifespan: float | None = None,
    ) -> Ack:
        """Apply removals then additions atomically, as one changeset; return the ack (`send`)."""
        cs = self.changeset(
            added,
            removed,
            inferred_added=inferred_added,
            inferred_removed=inferred_removed,
            cause=cause,
            lifespan=lifespan,
        )
        return self.send(cs, timeout=timeout, strict=strict)

    @contextmanager
    def transaction(self, *, timeout: float = 5.0) -> Iterator[Transaction]:
        """Collect additions and removals, then send them as one changeset on exit."""
        tx = Transaction()
        yield tx
        tx.id = self.apply(tx.added, tx.removed, timeout=timeout)

    # Reading

    def _ask(self, request: dict, timeout: float, stale: bool | None = None) -> dict:
        # The store gives up a little before the caller does, so the caller hears why.
        request["limit"] = max(0.05, timeout - max(0.1, min(1.0, timeout * 0.1)))
        if self.stale if stale is None else stale:
            request["stale"] = True  # see docs/wire-format.md
        return ask_store(self.session, self._key("query"), pack(request), timeout, what="query")

    def _template(self, template: TemplateLike) -> Template:
        try:
            return Template.of(template, self.prefixes)
        except TemplateError:
            if not isinstance(template, str):
                raise
            self.load_prefixes()  # the prefix may be registered in the space
            return Template.of(template, self.prefixes)

    def _graph(self, reply: dict) -> Graph:
        graph = Graph()
        for t in _triples(reply):
            graph.add(t)
        for name, ns in self.prefixes.as_dict().items():
            graph.bind(name, ns, override=True)
        return graph

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

    def _snapshot(self, template: Template, timeout: float) -> dict:
        return self._ask({"op": "snapshot", "template": template.to_wire()}, timeout)

    def load_prefixes(self, *, timeout: float = 5.0) -> PrefixMap:
        """Learn the prefixes registered in the space (for templates and display); return them."""
        reply = self._ask({"op": "prefixes"}, timeout)
        bindings = reply.get("prefixes") or {}
        if isinstance(bindings, dict):
            self.prefixes.update({str(k): str(v) for k, v in bindings.items()})
        return self.prefixes

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
        reply = ask_store(self.session, key, pack(request), timeout, what="log request")
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
            reply = ask_store(self.session, self._key("why"), pack(request), timeout, what="why")
        except (SpaceUnavailable, SpaceTimeout) as exc:
            raise NoReasoner(
                f"no reasoner answered on space {self.space!r} within {timeout:g} s "
                "(is one running? `tspace up` starts one)"
            ) from exc
        found = reply.get("explanations") or []
        if not isinstance(found, list):
            raise MalformedPayload("the reasoner's 'explanations' is not a list")
        return [Explanation.from_wire(w) for w in found]

    # Watching

    def subscribe(
        self,
        template: TemplateLike,
        callback: Callback,
        *,
        snapshot: bool | str = False,
        timeout: float = 5.0,
        skip_own: bool = False,
        scope: list[Scope] | None = None,
    ) -> Subscription:
        """Call `callback(change)` for every later changeset with triples matching `template`.

        With `snapshot=True` the first call carries the current matching state.
        Callbacks run in this handle's dispatcher thread, one at a time, in store order.
        `skip_own` leaves out the changesets this handle's agent wrote before
        their terms are parsed (a big change costs nothing to ignore).

        `scope`, (subject, predicate) pairs (each None, a term, or `"IRI-prefix*"`:
        `[(AC.robot7, None), ("ac:robot7_*", None)]`), asks only for the triples
        of those subjects and predicates: the router sends nothing else, so a
        robot's agent does not even receive the rest of a fleet's traffic. A
        changeset then comes in parts, by subject and predicate: those that arrive
        together are delivered as one change, a late one as another with the same
        id and seq; parts of one key come in store order, with no gap. See
        docs/wire-format.md. Its snapshot holds the scope's state, or, with
        `snapshot="all"`, everything matching `template` (the knowledge a robot's
        agent reads once, whose changes do not concern it).

        Raises:
            SpaceUnavailable: no store answered (the sequence number is needed to fill gaps).
            InputError: a malformed scope.
        """
        t = self._template(template)
        if not self._watchdogs:
            self._watch_store()
        skip_agent = self.agent if skip_own else None
        if scope is None:
            sub = Subscription(self._dispatcher, t, callback, skip_agent=skip_agent)
            sub_keys = [self._key("changes")]
        else:
            sub = ScopedSubscription(
                self._dispatcher,
                t,
                callback,
                space=self.space,
                selectors=self._selectors(scope),
                skip_agent=skip_agent,
            )
            sub_keys = sub.keys
        self._dispatcher.add(sub)
        self._subscriptions.add(sub)
        try:
            for key in sub_keys:
                sub.attach(self.session.declare_subscriber(key, self._dispatcher.feed(sub)))
            if snapshot:
                reply = self._snapshot(t, timeout)
                seq = int(reply.get("seq") or 0)
                state = list(dict.fromkeys(_triples(reply)))
                if isinstance(sub, ScopedSubscription) and snapshot != "all":
                    state = [x for x in state if sub.selects(x)]
                initial = Change(
                    agent="",
                    seq=seq,
                    added=state,
                    bindings=[b for x in state if (b := t.match(x)) is not None],
                )
            else:
                seq, initial = self._seq(timeout), None
        except BaseException:
            self.unsubscribe(sub)
            raise
        if isinstance(sub, ScopedSubscription):
            sub.start(seq)
        self._dispatcher.mark_ready(sub, seq, initial)
        return sub

    def _selectors(self, scope: list[Scope]) -> list[str]:
        try:
            return selectors(scope, self.prefixes)
        except InputError:
            self.load_prefixes()  # the prefix may be registered in the space
            return selectors(scope, self.prefixes)

    def _watch_store(self) -> None:
        """Fetch changes missed while a link was down from the store's log.

        On this session's reconnection, when the leading store's token comes back
        (a cut between it and us), and when the store's heartbeat shows a later
        sequence number, so a lost change shows up even when no later one follows.
        """
        self._watchdogs = [
            self.session.info.declare_transport_events_listener(self._on_transport),
            self.session.liveliness().declare_subscriber(
                f"{keys.ROOT}/@leader/*", self._on_transport
            ),
            self.session.declare_subscriber(self._key("seq"), self._on_heartbeat),
        ]

    def _on_transport(self, event: zenoh.TransportEvent | zenoh.Sample) -> None:
        if event.kind == zenoh.SampleKind.PUT:
            self._dispatcher.catch_up()

    def _on_heartbeat(self, sample: zenoh.Sample) -> None:
        try:
            beat = unpack(sample.payload.to_bytes())
            seq = int(beat["seq"])  # type: ignore[index]
        except (MalformedPayload, TypeError, KeyError, ValueError):
            log.warning("malformed heartbeat on %s skipped", sample.key_expr)
            return
        self._dispatcher.catch_up(seq)

    def unsubscribe(self, sub: Subscription) -> None:
        """Stop a subscription."""
        sub.close()
        self._subscriptions.discard(sub)

    def _seq(self, timeout: float) -> int:
        reply = ask_store(
            self.session, self._key("log"), pack({"from": 1, "to": 0}), timeout, what="log request"
        )
        return int(reply.get("seq") or 0)

    def _fetch_log(self, first: int, last: int) -> tuple[list[bytes], int]:
        reply = ask_store(
            self.session,
            self._key("log"),
            pack({"from": first, "to": last}),
            5.0,
            what="log request",
        )
        return [bytes(p) for p in reply.get("changes") or ()], int(reply.get("seq") or 0)


def _triples(reply: dict) -> Iterator[Triple]:
    for name in (keys.ASSERTED, keys.INFERRED):
        for t in reply.get(name) or ():
            yield triple_from_nt(t)


class Transaction:
    """Additions and removals collected for one changeset (see `TripleSpace.transaction`)."""

    def __init__(self) -> None:
        self.added: list[Triple] = []
        self.removed: list[Triple] = []
        self.id: str | None = None

    def add(self, triple: Triple) -> None:
        """Add a triple when the transaction commits."""
        self.added.append(triple)

    def remove(self, triple: Triple) -> None:
        """Remove a triple when the transaction commits (before the additions)."""
        self.removed.append(triple)


def _used_prefixes(cs: Changeset, sources: list[Triples], own: PrefixMap) -> dict[str, str]:
    """Return the prefix bindings (of the given graphs and our own) whose namespace is used."""
    by_ns = {ns: name for name, ns in own.as_dict().items()}
    for source in sources:
        if isinstance(source, Graph):
            by_ns.update({str(ns): str(n) for n, ns in source.namespaces() if n})
    used: dict[str, str] = {}
    for t in (*cs.added, *cs.removed, *cs.inferred_added, *cs.inferred_removed):
        for term in t:
            if isinstance(term, URIRef):
                ns = _namespace(term)
                if ns in by_ns:
                    used[by_ns[ns]] = ns
    return used


_NAMESPACES: dict[URIRef, str] = {}


def _namespace(iri: URIRef) -> str:
    """Return an IRI up to its last `#` or `/` (memoized: a big changeset repeats its IRIs)."""
    ns = _NAMESPACES.get(iri)
    if ns is None:
        if len(_NAMESPACES) >= CACHED:
            _NAMESPACES.clear()
        text = str(iri)
        ns = _NAMESPACES[iri] = text[: max(text.rfind("#"), text.rfind("/")) + 1]
    return ns
