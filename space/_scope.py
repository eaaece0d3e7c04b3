"""What a scope selects: the key expressions of its `<s>/<p>` selectors, and matchers of
the key chunks each selects (a subscription's own check of what Zenoh delivered and of
the ends it sends back; see `space._scoped`)."""

from __future__ import annotations

import re
from collections.abc import Callable

import zenoh
from rdflib import BNode, Literal, URIRef

from space import keys
from space._parts import term_chunk
from space.errors import InputError
from space.prefixes import PrefixMap

Matcher = Callable[[str], object]  # truthy for a key chunk a selector's chunk matches


def patterns(selector: str) -> tuple[Matcher, Matcher]:
    """Return matchers of the subject and predicate chunks a selector `<s>/<p>` selects."""
    return tuple(_matcher(chunk) for chunk in selector.split("/"))  # type: ignore[return-value]


def exact(selector: str) -> tuple[str | None, str | None]:
    """Return a selector's subject and predicate chunks, None for one with a wildcard."""
    s, p = selector.split("/")
    return tuple(None if c == "*" or "$*" in c else c for c in (s, p))  # type: ignore[return-value]


def _matcher(chunk: str) -> Matcher:
    """Return a matcher of the key chunks one chunk of a key expression matches.

    `*` matches any chunk, `$*` any text within one (as Zenoh has them); a part's
    chunks never start with `@`, so verbatim chunks need no care here.
    """
    if chunk == "*":
        return bool
    return re.compile(".*".join(re.escape(piece) for piece in chunk.split("$*")), re.S).fullmatch


def through(part_keys: list[str]) -> list[tuple[str, int]]:
    """Return, for each selector's key expression, a key it matches and how many of them do.

    The key is the key expression with its wildcards filled (`*`, `**` -> `_`, `$*` -> ``).
    Empty when a selector has no such key: then ends are not sent back, and delivery
    waits for the rest of a changeset of many only as long as parts keep coming.
    """
    exprs = [zenoh.KeyExpr(k) for k in part_keys]
    through = []
    for expr in exprs:
        chunks_ = [
            ("_" if c in ("*", "**") else c.replace("$*", "")) or "_" for c in str(expr).split("/")
        ]
        try:
            key = zenoh.KeyExpr("/".join(chunks_))
        except (zenoh.ZError, ValueError):
            return []
        if not expr.intersects(key):
            return []
        through.append((str(key), sum(1 for e in exprs if e.intersects(key))))
    return through


def selector_key(space: str, selector: str) -> str:
    """Return the key expression of a selector `<s>/<p>` (two chunks, wildcards allowed).

    It matches the parts about a subject `<s>` matches whose key names a predicate
    `<p>` matches (`<s>/**/<p>/**`; `<s>/*/**` for any predicate).

    Raises:
        InputError: not two chunks, or not a valid key expression.
    """
    chunks_ = selector.split("/")
    if len(chunks_) != 2 or "**" in chunks_:
        raise InputError(f"scope {selector!r}: write SUBJECT/PREDICATE, each one key chunk")
    s, p = chunks_
    key = keys.part_key(space, s, "*/**" if p == "*" else f"**/{p}/**")
    try:
        zenoh.KeyExpr(key)
    except (zenoh.ZError, ValueError) as exc:
        raise InputError(f"scope {selector!r}: not a key expression: {exc}") from exc
    return key


Scope = tuple[object, object]  # (subject, predicate): None, an rdflib term, or "IRI-prefix*"


def selectors(scope: list[Scope], prefixes: PrefixMap) -> list[str]:
    """Return the `<s>/<p>` selectors of a scope.

    Each of a pair's two positions is None (any), an rdflib term (exactly it), or
    a string ending in `*`: every IRI that starts with what comes before it (an
    IRI, or `pfx:local` expanded with `prefixes`), e.g. `"ac:robot7_*"`.

    Raises:
        InputError: a position is none of those, or names an unknown prefix.
    """
    out = []
    for pair in scope:
        if not isinstance(pair, tuple) or len(pair) != 2:
            raise InputError(f"scope {pair!r}: give (subject, predicate) pairs")
        for s in _chunks(pair[0], prefixes):
            for p in _chunks(pair[1], prefixes):
                out.append(f"{s}/{p}")
    return list(dict.fromkeys(out))


def _chunks(position: object, prefixes: PrefixMap) -> list[str]:
    if position is None:
        return ["*"]
    if isinstance(position, URIRef | Literal | BNode):
        return [term_chunk(position)]
    if isinstance(position, str):
        if not position.endswith("*"):
            raise InputError(f"scope {position!r}: an IRI prefix ends with '*'")
        return [f"<{keys.escape(_iri(position[:-1], prefixes))}$*>"]
    raise InputError(f"scope position {position!r}: None, an RDF term or 'IRI-prefix*'")


def _iri(text: str, prefixes: PrefixMap) -> str:
    if "://" in text or text.startswith("urn:"):
        return text
    iri = prefixes.expand(text)
    if iri is None:
        raise InputError(f"scope {text + '*'!r}: unknown prefix")
    return str(iri)
