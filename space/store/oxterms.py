"""Wire terms (N-Triples texts) <-> pyoxigraph terms: the store's one term conversion.

Every term that enters the store is checked here (a valid IRI, literal or
blank node label, within `MAX_TERM` characters), so nothing invalid reaches
the database: an IRI such as `<http://a b>` is refused at the edge instead of
breaking every later CONSTRUCT of its space.

Blank nodes are stored skolemized, as `urn:tspace:bnode:<label>` IRIs: SPARQL
UPDATE (the one atomic call that both removes and adds) cannot name a stored
blank node, so a blank node must be an IRI inside the database. Every answer
turns those IRIs back into `_:<label>`.
"""

from __future__ import annotations

import re
from functools import lru_cache
from itertools import chain

import pyoxigraph as ox

from space.errors import MalformedPayload

OxTerm = ox.NamedNode | ox.BlankNode | ox.Literal
OxTriple = tuple[OxTerm, OxTerm, OxTerm]

MAX_TERM = 16_384  # characters of one term's N-Triples text (docs/wire-format.md)
SKOLEM = "urn:tspace:bnode:"
XSD_STRING = "http://www.w3.org/2001/XMLSchema#string"
_CACHED = 8192

_LITERAL_RE = re.compile(
    r'^"((?:[^"\\\n\r]|\\.)*)"(?:\^\^<([^<>"{}|^`\\\x00-\x20]*)>|@([A-Za-z]+(?:-[A-Za-z0-9]+)*))?$',
    re.S,
)
_IRI_RE = re.compile(r'^<([^<>"{}|^`\\\x00-\x20]*)>$')
_BNODE_RE = re.compile(r"^_:([A-Za-z0-9_](?:[A-Za-z0-9_.\-]*[A-Za-z0-9_\-])?)$")
_UNESCAPE_RE = re.compile(r'\\(u[0-9A-Fa-f]{4}|U[0-9A-Fa-f]{8}|[tbnrf"\'\\])')
_SIMPLE = {"t": "\t", "b": "\b", "n": "\n", "r": "\r", "f": "\f", '"': '"', "'": "'", "\\": "\\"}


def _unescape(text: str) -> str:
    if "\\" not in text:
        return text
    rest = _UNESCAPE_RE.sub("", text)
    if "\\" in rest:
        raise MalformedPayload(f"bad escape in literal {text[:80]!r}")

    def one(match: re.Match[str]) -> str:
        code = match.group(1)
        if code[0] in "uU":
            point = int(code[1:], 16)
            if point > 0x10FFFF or 0xD800 <= point <= 0xDFFF:
                raise MalformedPayload(f"bad code point escape \\{code}")
            return chr(point)
        return _SIMPLE[code]

    return _UNESCAPE_RE.sub(one, text)


def term(text: object) -> OxTerm:
    """Return the pyoxigraph term of one N-Triples term text.

    Raises:
        MalformedPayload: not a string, too long, or not a valid IRI, literal or blank node.
    """
    if not isinstance(text, str) or not text:
        raise MalformedPayload(f"a term is a non-empty N-Triples string, got {_short(text)}")
    return _term(text)


@lru_cache(maxsize=_CACHED)
def _term(text: str) -> OxTerm:
    if len(text) > MAX_TERM:
        raise MalformedPayload(f"a term is at most {MAX_TERM} characters, got {len(text)}")
    try:
        first = text[0]
        if first == "<":
            match = _IRI_RE.match(text)
            if match is None:
                raise MalformedPayload(f"not an N-Triples IRI: {_short(text)}")
            return ox.NamedNode(match.group(1))
        if first == '"':
            match = _LITERAL_RE.match(text)
            if match is None:
                raise MalformedPayload(f"not an N-Triples literal: {_short(text)}")
            lexical, datatype, lang = match.groups()
            value = _unescape(lexical)
            if lang:
                return ox.Literal(value, language=lang)
            if datatype and datatype != XSD_STRING:
                return canonical(ox.Literal(value, datatype=ox.NamedNode(datatype)))
            return ox.Literal(value)
        match = _BNODE_RE.match(text)
        if match is not None:
            return ox.NamedNode(SKOLEM + match.group(1))
    except ValueError as exc:  # pyoxigraph's verdict on an IRI or a language tag
        raise MalformedPayload(f"invalid RDF term {_short(text)}: {exc}") from None
    raise MalformedPayload(f"not an N-Triples term: {_short(text)}")


def triple(parts: object) -> OxTriple:
    """Return the pyoxigraph triple of a `[s, p, o]` list of N-Triples texts.

    Raises:
        MalformedPayload: not three terms, a literal as subject, or a predicate that is not an IRI.
    """
    if not isinstance(parts, list | tuple) or len(parts) != 3:
        raise MalformedPayload(f"a triple is a list of three terms, got {_short(parts)}")
    s, p, o = term(parts[0]), term(parts[1]), term(parts[2])
    if isinstance(s, ox.Literal) or not isinstance(p, ox.NamedNode) or p.value.startswith(SKOLEM):
        raise MalformedPayload(f"not a valid RDF triple: {_short(parts)}")
    return s, p, o


def triples(rows: list) -> list[OxTriple]:
    """Return the pyoxigraph triples of a list of `[s, p, o]` texts, parsed in bulk.

    Raises:
        MalformedPayload: as `triple`.
    """
    return parse_rows(rows)[0]


def parse_rows(rows: list) -> tuple[list[OxTriple], bool]:
    """Return the triples of `[s, p, o]` texts, and whether each row is its triple's own text.

    The rows are joined into one N-Triples document, which one regular
    expression checks line by line (so no text can carry a second term, a
    comment or a line end into it) and Oxigraph's parser reads at once. Where
    every row is plain (no escape, no language tag, no literal turned into its
    canonical form) the rows are the texts the store publishes, and no term is
    turned back into text. Anything refused is parsed again term by term, for
    an error that names the term.

    Raises:
        MalformedPayload: as `triple`.
    """
    try:
        document = "".join([f"{s} {p} {o} .\n" for s, p, o in rows])
    except (TypeError, ValueError):  # a row that is not three items
        document = ""
    if (
        document.count("\n") == len(rows)
        and _DOCUMENT_RE.fullmatch(document) is not None
        and max(map(len, chain.from_iterable(rows)), default=0) <= MAX_TERM
    ):
        try:
            quads = list(ox.parse(document, format=ox.RdfFormat.N_TRIPLES))
        except (SyntaxError, ValueError):
            quads = []
        if len(quads) == len(rows):
            blank = "_:" in document
            written = [_skolem(q.object) for q in quads] if blank else [q.object for q in quads]
            objects = canonical_all(written)
            plain = not blank and "\\" not in document and '"@' not in document
            if plain and objects is not written:
                plain = all(a == b for a, b in zip(objects, written, strict=True))
            subjects = [_skolem(q.subject) for q in quads] if blank else [q.subject for q in quads]
            parsed = [(s, q.predicate, o) for s, q, o in zip(subjects, quads, objects, strict=True)]
            return parsed, plain  # type: ignore[return-value]
    return [triple(row) for row in rows], False


def plain_rows(rows: list) -> list[list[str]] | None:
    """Return `[s, p, o]` texts that are already their stored triples' own text; else None.

    Plain means: every row one valid triple (as `parse_rows` checks it), no
    escape, language tag or blank node in it, and every XSD-typed literal an
    integer, decimal, double or boolean in its canonical form. Such texts are
    what the store holds, publishes and answers, term for term, so a changeset
    of them is decided and committed as text (`render.py`), no term of it
    becoming a Python object. None: the caller parses the rows term by term
    (`triples`), which says what is wrong.
    """
    try:
        document = "".join([f"{s} {p} {o} .\n" for s, p, o in rows])
    except (TypeError, ValueError):  # a row that is not three items
        return None
    if (
        "\\" in document
        or '"@' in document
        or "_:" in document
        or document.count(_XSD_TYPED) != len(_CANONICAL_VALUES.findall(document))
        or document.count("\n") != len(rows)
        or _DOCUMENT_RE.fullmatch(document) is None
        or max(map(len, chain.from_iterable(rows)), default=0) > MAX_TERM
    ):
        return None
    try:
        count = sum(1 for _ in ox.parse(document, format=ox.RdfFormat.N_TRIPLES))
    except (SyntaxError, ValueError):
        return None
    return rows if count == len(rows) else None


_IRI = r'<[^<>"{}|^`\\\x00-\x20]*>'
_BLANK = r"_:[A-Za-z0-9_](?:[A-Za-z0-9_.\-]*[A-Za-z0-9_\-])?"
_LITERAL = r'"[^"\\\n\r]*(?:\\.[^"\\\n\r]*)*"(?:\^\^' + _IRI + r"|@[A-Za-z]+(?:-[A-Za-z0-9]+)*)?"
_XSD_TYPED = '"^^<http://www.w3.org/2001/XMLSchema#'
_CANONICAL_VALUES = re.compile(  # XSD literals Oxigraph holds in the very same form
    r'"(?:0|-?[1-9][0-9]{0,17})"\^\^<http://www\.w3\.org/2001/XMLSchema#integer> \.\n'
    r'|"(?:0|-?[1-9][0-9]{0,14}|-?(?:0|[1-9][0-9]{0,14})\.[0-9]{0,14}[1-9])"'
    r"\^\^<http://www\.w3\.org/2001/XMLSchema#decimal> \.\n"
    r'|"(?:0|-?[1-9][0-9]{0,14}|-?(?:0|[1-9][0-9]{0,6})\.[0-9]{0,6}[1-9])"'
    r"\^\^<http://www\.w3\.org/2001/XMLSchema#double> \.\n"
    r'|"(?:true|false)"\^\^<http://www\.w3\.org/2001/XMLSchema#boolean> \.\n'
)
_DOCUMENT_RE = re.compile(
    rf"(?:(?:{_IRI}|{_BLANK}) (?!<{SKOLEM}){_IRI} (?:{_IRI}|{_BLANK}|{_LITERAL}) \.\n)*"
)


def canonical(node: OxTerm) -> OxTerm:
    """Return a literal as the database will hold it: XSD values in their canonical form.

    Oxigraph stores numbers, booleans, dates and durations by value, so
    `"2.0"^^xsd:decimal` comes back as `"2"^^xsd:decimal`. Turning every such
    literal into that form where it enters keeps what is published, acknowledged
    and read the same term.
    """
    return canonical_all([node])[0]


def canonical_all(nodes: list[OxTerm]) -> list[OxTerm]:
    """Return `canonical` of each term, the literals not seen lately put through one scratch store.

    The scratch store is a fresh one each time: an in-memory Oxigraph store that
    is cleared and reused keeps the old versions, and its `clear` slows down
    with every use (20,000 literals one by one took 15 s instead of 0.3).
    """
    known = {n: _CANONICAL.get(n) for n in nodes if _may_change(n)}  # threads share _CANONICAL
    todo = [n for n, held in known.items() if held is None]
    if todo:
        scratch = ox.Store()  # in memory
        scratch.extend(
            ox.Quad(ox.NamedNode(f"{_SCRATCH}{i}"), _SCRATCH_NODE, n) for i, n in enumerate(todo)
        )
        if len(_CANONICAL) + len(todo) > _CACHED:
            _CANONICAL.clear()
        for q in scratch:
            n = todo[int(q.subject.value[len(_SCRATCH) :])]
            known[n] = _CANONICAL[n] = q.object
    if not known:
        return nodes
    return [n if (held := known.get(n)) is None else held for n in nodes]


def _may_change(node: OxTerm) -> bool:
    """Return whether a literal may have another canonical form (strings and integers in
    theirs, the bulk of what robots write, are known not to)."""
    if not isinstance(node, ox.Literal):
        return False
    datatype = node.datatype
    if datatype == _INTEGER:
        return _CANONICAL_INTEGER.fullmatch(node.value) is None
    return datatype != _STRING and datatype.value.startswith(_XSD)


_XSD = "http://www.w3.org/2001/XMLSchema#"
_STRING = ox.NamedNode(XSD_STRING)
_INTEGER = ox.NamedNode(_XSD + "integer")
_CANONICAL_INTEGER = re.compile(r"0|-?[1-9][0-9]*")
_SCRATCH = "urn:tspace:canonical:"
_SCRATCH_NODE = ox.NamedNode("urn:tspace:canonical")
_CANONICAL: dict[OxTerm, OxTerm] = {}  # literal as written -> as stored, the latest ones


def _skolem(node: object) -> OxTerm:
    if isinstance(node, ox.BlankNode):
        return ox.NamedNode(SKOLEM + node.value)
    return node  # type: ignore[return-value]


@lru_cache(maxsize=_CACHED)
def text(node: OxTerm) -> str:
    """Return the N-Triples text of a stored term (skolem IRIs back as blank nodes)."""
    if isinstance(node, ox.NamedNode) and node.value.startswith(SKOLEM):
        return "_:" + node.value[len(SKOLEM) :]
    if isinstance(node, ox.BlankNode):
        return "_:" + node.value
    return str(node)


def triple_text(t: OxTriple) -> list[str]:
    """Return the `[s, p, o]` N-Triples texts of a stored triple."""
    return [text(t[0]), text(t[1]), text(t[2])]


def sparql(node: OxTerm) -> str:
    """Return a term as SPARQL text (skolem IRIs stay IRIs: that is what the database holds)."""
    return str(node)


def _short(value: object) -> str:
    shown = repr(value)
    return shown if len(shown) <= 120 else shown[:117] + "..."
