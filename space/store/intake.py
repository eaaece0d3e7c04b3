"""Check every request at the edge: field types, sizes and terms, before any work is done.

A request that fails here is answered with one error naming the field and the
limit, and touches nothing else: no state is created for its space, no other
request of its batch is affected. The limits are documented in
docs/wire-format.md; change them there too.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from space.changeset import WIRE_VERSION, hlc_key, unpack
from space.errors import InputError, MalformedPayload
from space.lifespan import check_lifespan
from space.store import oxterms
from space.store.oxterms import OxTerm, OxTriple

MAX_PAYLOAD = 16 * 1024 * 1024  # bytes of one request
MAX_TRIPLES = 100_000  # triples of one changeset, all four lists together
MAX_ID = 200  # characters of an id, agent name or timestamp
MAX_PREFIXES = 256  # bindings in one changeset
LISTS = ("add", "del", "iadd", "idel")
GRAPHS = {"all": "all", "asserted": "t", "inferred": "i"}
QUERY_OPS = ("query", "read", "take", "snapshot", "sparql", "prefixes")


@dataclass
class WriteRequest:
    """A changeset as a writer sent it, its terms checked and converted."""

    id: str
    agent: str = ""
    ts: str = ""
    cause: str | None = None
    prefixes: dict[str, str] = field(default_factory=dict)
    added: list[OxTriple] = field(default_factory=list)
    removed: list[OxTriple] = field(default_factory=list)
    inferred_added: list[OxTriple] = field(default_factory=list)
    inferred_removed: list[OxTriple] = field(default_factory=list)
    lifespan: float | None = None  # seconds the added triples live (None: permanent)
    plain: list[list[str]] | None = None  # the additions, when only added and plain (oxterms)

    def parse_plain(self) -> None:
        """Turn plain additions into terms, for the store's term-by-term path."""
        if self.plain is not None:
            self.added, self.plain = oxterms.triples(self.plain), None


@dataclass
class QueryRequest:
    """A request on `@/query`, checked."""

    op: str
    template: tuple[OxTerm | None, OxTerm | None, OxTerm | None] = (None, None, None)
    graph: str = "all"
    text: str = ""
    limit: float | None = None  # seconds the requester allows (capped by the store's own)
    id: str = ""  # a take's request id: a retry gets the first outcome
    agent: str = ""
    ts: str = ""
    lifespans: bool = False  # also answer each asserted triple's remaining life


def _string(wire: dict, name: str, *, required: bool = False, limit: int = MAX_ID) -> str:
    value = wire.get(name)
    if value is None or (value == "" and not required):
        if required:
            raise MalformedPayload(f"'{name}' is required")
        return ""
    if not isinstance(value, str) or not value:
        raise MalformedPayload(f"'{name}' must be a non-empty string, got {type(value).__name__}")
    if len(value) > limit:
        raise MalformedPayload(f"'{name}' is at most {limit} characters, got {len(value)}")
    return value


def _stamp(wire: dict) -> str:
    ts = _string(wire, "ts")
    if ts:
        hlc_key(ts)
    return ts


def _lifespan(wire: dict) -> float | None:
    try:
        return check_lifespan(wire.get("lifespan"))
    except InputError as exc:
        raise MalformedPayload(f"'lifespan': {exc}") from exc


def _map(payload: bytes) -> dict:
    if len(payload) > MAX_PAYLOAD:
        raise MalformedPayload(f"a request is at most {MAX_PAYLOAD} bytes, got {len(payload)}")
    wire = unpack(payload)
    if not isinstance(wire, dict):
        raise MalformedPayload("a request is a msgpack map")
    return wire


def write_request(payload: bytes) -> WriteRequest:
    """Decode and check a changeset sent to `@/write`.

    Raises:
        MalformedPayload: naming the first field or term that is wrong or too big.
    """
    wire = _map(payload)
    version = wire.get("v", WIRE_VERSION)
    if version != WIRE_VERSION:
        raise MalformedPayload(f"unknown changeset version {version!r} (this is {WIRE_VERSION})")
    req = WriteRequest(
        id=_string(wire, "id", required=True),
        agent=_string(wire, "agent"),
        ts=_stamp(wire),
        cause=_string(wire, "cause") or None,
        lifespan=_lifespan(wire),
    )
    prefixes = wire.get("prefixes") or {}
    if not isinstance(prefixes, dict) or len(prefixes) > MAX_PREFIXES:
        raise MalformedPayload(f"'prefixes' is a map of at most {MAX_PREFIXES} name -> IRI")
    for name, ns in prefixes.items():
        if not isinstance(name, str) or not isinstance(ns, str) or len(name) > MAX_ID:
            raise MalformedPayload(f"a prefix binding is two strings, got {name!r}: {ns!r}")
        oxterms.term(f"<{ns}>")  # a namespace is an IRI
        req.prefixes[name] = ns
    lists = []
    count = 0
    for name in LISTS:
        listed = wire.get(name) or []
        if not isinstance(listed, list):
            raise MalformedPayload(f"'{name}' must be a list of triples")
        count += len(listed)
        if count > MAX_TRIPLES:
            raise MalformedPayload(f"a changeset holds at most {MAX_TRIPLES} triples")
        lists.append(listed)
    if lists[0] and not any(lists[1:]):
        req.plain = oxterms.plain_rows(lists[0])
        if req.plain is not None:
            return req
    # One parse for every list: most writes are small, and a parse has a cost of its own.
    parsed = oxterms.triples([row for listed in lists for row in listed]) if count else []
    split, first = [], 0
    for listed in lists:
        split.append(parsed[first : first + len(listed)])
        first += len(listed)
    req.added, req.removed, req.inferred_added, req.inferred_removed = split
    return req


def query_request(payload: bytes) -> QueryRequest:
    """Decode and check a request sent to `@/query`.

    Raises:
        MalformedPayload: an unknown op, or a field of the wrong type or size.
    """
    wire = _map(payload)
    op = wire.get("op")
    if op not in QUERY_OPS:
        raise MalformedPayload(f"unknown query op {op!r} (one of {', '.join(QUERY_OPS)})")
    req = QueryRequest(op=op)
    limit = wire.get("limit")
    if limit is not None:
        if isinstance(limit, bool) or not isinstance(limit, int | float) or not 0 < limit < 1e6:
            raise MalformedPayload(f"'limit' is a positive number of seconds, got {limit!r}")
        req.limit = float(limit)
    if op == "sparql":
        text = wire.get("text")
        if not isinstance(text, str) or not text.strip():
            raise MalformedPayload("a SPARQL request needs its text")
        if len(text) > MAX_PAYLOAD:
            raise MalformedPayload(f"a SPARQL text is at most {MAX_PAYLOAD} characters")
        req.text = text
        return req
    template = wire.get("template")
    if template is not None:
        if not isinstance(template, list | tuple) or len(template) != 3:
            raise MalformedPayload(f"a template is three terms or nulls, got {template!r:.120}")
        req.template = tuple(None if t is None else oxterms.term(t) for t in template)  # type: ignore[assignment]
    graph = wire.get("graph", "asserted" if op == "take" else "all")
    if graph not in GRAPHS:
        raise MalformedPayload(f"unknown graph {graph!r:.60} (all, asserted or inferred)")
    req.graph = GRAPHS[graph]
    req.lifespans = wire.get("lifespan") is True
    if op == "take":
        if req.graph != "t":
            raise MalformedPayload("take removes asserted triples only (graph 'asserted')")
        req.id = _string(wire, "id")
        req.agent = _string(wire, "agent")
        req.ts = _stamp(wire)
    return req


def log_request(payload: bytes, seq: int) -> tuple[int, int]:
    """Return the `(from, to)` range of a `@/log` request (`to` defaults to `seq`).

    Raises:
        MalformedPayload: not a map of two non-negative integers.
    """
    wire = _map(payload) if payload else {}
    first, last = wire.get("from", 1), wire.get("to", seq)
    for name, value in (("from", first), ("to", last)):
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < 2**63:
            raise MalformedPayload(f"'{name}' is a non-negative integer, got {value!r:.60}")
    return first, last
