"""What every part of a `TripleSpace` handle shares: its state and the store's request keys.

`TripleSpace` is one class to its users; its reads (`_reads.py`), its watching
(`_watching.py`) and its writes (`client.py`) live apart, on this common base.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import zenoh
from rdflib import Graph

from space import keys
from space._dispatch import Dispatcher
from space._request import Queriers, ask_store
from space._subscription import Subscription
from space.changeset import pack
from space.errors import TemplateError
from space.lifespan import check_lifespan
from space.prefixes import PrefixMap
from space.template import Template
from space.terms import Triple, triple_from_nt

TemplateLike = Template | tuple | str | None
Triples = Iterable[Triple] | Graph


class Handle:
    """A handle's state, and how it asks the store (see `TripleSpace`)."""

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
        dispatch_thread: bool = True,
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
        self._queriers = Queriers(session)  # the store's services, asked on declared queriers
        self._dispatcher = Dispatcher(self._fetch_log, own_thread=dispatch_thread)
        self._subscriptions: set[Subscription] = set()
        self._watchdogs: list = []

    def _key(self, service: str) -> str:
        key = keys.service_key(self.space, service)
        if self.writer is not None and service in ("write", "query"):
            return f"{key}/{self.writer}"
        return key

    def _ask(self, request: dict, timeout: float, stale: bool | None = None) -> dict:
        # The store gives up a little before the caller does, so the caller hears why: a
        # tenth of the timeout, at least 0.25 s (its answer crossing a loaded host) and at most 1.
        request["limit"] = max(0.05, timeout - max(0.25, min(1.0, timeout * 0.1)))
        if self.stale if stale is None else stale:
            request["stale"] = True  # see docs/wire-format.md
        return ask_store(self._queriers, self._key("query"), pack(request), timeout, what="query")

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

    def _snapshot(self, template: Template, timeout: float) -> dict:
        return self._ask({"op": "snapshot", "template": template.to_wire()}, timeout)

    def load_prefixes(self, *, timeout: float = 5.0) -> PrefixMap:
        """Learn the prefixes registered in the space (for templates and display); return them."""
        reply = self._ask({"op": "prefixes"}, timeout)
        bindings = reply.get("prefixes") or {}
        if isinstance(bindings, dict):
            self.prefixes.update({str(k): str(v) for k, v in bindings.items()})
        return self.prefixes

    def _seq(self, timeout: float) -> int:
        reply = ask_store(
            self._queriers,
            self._key("log"),
            pack({"from": 1, "to": 0}),
            timeout,
            what="log request",
        )
        return int(reply.get("seq") or 0)

    def _fetch_log(self, first: int, last: int) -> tuple[list[bytes], int]:
        reply = ask_store(
            self._queriers,
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
