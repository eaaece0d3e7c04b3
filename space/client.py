"""TripleSpace: the Triple Space Computing operations over a Zenoh session.

After otsopack/TripCom: `write`, `read`, `query`, `take`, `subscribe`, each
with a timeout. Every blocking call waits for the store; none may be called
from inside a Zenoh callback (subscription callbacks run in the library's own
dispatcher thread, where they are fine). The class is assembled from its
reads (`_reads.py`) and its watching (`_watching.py`) on a shared base
(`_handle.py`); its writes are here.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from types import TracebackType
from typing import TYPE_CHECKING

from rdflib import Graph, URIRef

from space import keys
from space._handle import TemplateLike, Triples
from space._reads import Reads
from space._request import Pending, ask_store
from space._session import open_session
from space._watching import Watching
from space.ack import Ack
from space.changeset import Changeset
from space.lifespan import check_lifespan
from space.prefixes import PrefixMap
from space.terms import CACHED, Triple

if TYPE_CHECKING:
    from space.identity import Identity

__all__ = ["TemplateLike", "Transaction", "TripleSpace", "Triples"]


class TripleSpace(Reads, Watching):
    """A handle on one space, over a Zenoh session.

    Built on a session you own (`TripleSpace(session, ...)`), it leaves the
    session open on `close()`; `TripleSpace.open(...)` opens its own session
    and closes it. Either way, use it as a context manager.
    """

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
        dispatch_thread: bool = True,
    ) -> TripleSpace:
        """Open a session to the routers at `connect` and a handle on `space`.

        Blocks until a router is reached. `prefixes` (name -> namespace IRI) are
        used in templates and sent with the changesets that use them, so the
        space learns them too. With `strict`, a write some of whose triples the
        store did not apply raises `NotApplied` (see `send`). With `identity`
        (`space.load_identity`), every link is mutual TLS with its certificate,
        and writes go under its name.
        `lifespan`: the default lifespan in seconds of every write of this handle
        (see `write`). With `dispatch_thread=False` the subscriptions' callbacks run
        on the thread that calls `deliver` in a loop (see `Watching.deliver`), not on
        a thread of the handle's own.

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
                dispatch_thread=dispatch_thread,
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
            steps.callback(self._queriers.close)  # after the dispatcher, whose fetches use them
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
        reply = ask_store(self._queriers, self._key("write"), cs.encode(), timeout, what="write")
        ack = Ack.of(cs.id, reply)
        return ack.check() if (self.strict if strict is None else strict) else ack

    def send_later(self, cs: Changeset, *, timeout: float = 5.0) -> Pending:
        """Send a changeset now and read the acknowledgement later (`send`'s pipelined twin).

        Returns at once; `result()` of what it returns blocks as `send` does and
        raises what `send` raises; its `ready()` says, without blocking, whether
        the store's reply is in (or the request ended without one). Changesets
        sent one after the other are applied in that order, so a writer may keep
        several in flight.
        """
        return Pending(self._queriers, self._key("write"), cs.encode(), timeout, what="write")

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
        return cs.id, Pending(self._queriers, self._key("write"), payload, timeout, what="write")

    def send_nowait(self, cs: Changeset) -> str:
        """Send a changeset without waiting (fire-and-forget twin of `send`); return its id."""
        self._queriers.put(self._key("write"), cs.encode())
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
