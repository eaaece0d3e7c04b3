"""Triple templates: triples whose positions may be wildcards or `?variables`."""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from rdflib import XSD, BNode, Literal, URIRef, Variable
from rdflib.namespace import RDF
from rdflib.term import Node

from space.errors import TemplateError
from space.prefixes import PrefixMap
from space.terms import Triple, to_nt, unescape

Slot = Node | None

_TOKEN_RE = re.compile(
    r"""\s*(?:
      (?P<iri><[^<>"\s]*>)
    | (?P<lit>"(?:[^"\\]|\\.)*"|'(?:[^'\\]|\\.)*')
      (?:@(?P<lang>[A-Za-z]+(?:-[A-Za-z0-9]+)*)
        |\^\^(?P<dt><[^<>\s]*>|[A-Za-z][\w.\-]*:[^\s]*))?
    | (?P<var>\?[A-Za-z_]\w*)
    | (?P<wild>\*|_|None)(?=\s|$)
    | (?P<num>[+-]?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?)(?=\s|$)
    | (?P<bnode>_:[\w\-]+)
    | (?P<pname>[A-Za-z][\w.\-]*:[^\s]*|:[^\s]*|a)(?=\s|$)
    )""",
    re.X,
)


_VAR_RE = re.compile(r"\?[A-Za-z_]\w*")


@dataclass(frozen=True)
class Template:
    """A triple pattern; `None` and `Variable` positions match anything.

    A position may also be given as a plain string `"?name"`, read as
    `Variable("name")`, as in template texts; any other plain string is
    refused (a string is not an RDF term: use `URIRef`, `Literal` or `parse`).
    """

    s: Slot = None
    p: Slot = None
    o: Slot = None

    def __post_init__(self) -> None:
        for name in ("s", "p", "o"):
            object.__setattr__(self, name, _position(getattr(self, name)))

    @classmethod
    def of(
        cls, value: Template | Iterable[Slot] | str | None, prefixes: PrefixMap | None = None
    ) -> Template:
        """Return a template from a Template, a 3-tuple, a text (see `parse`) or None (all)."""
        if value is None:
            return cls()
        if isinstance(value, Template):
            return value
        if isinstance(value, str):
            return cls.parse(value, prefixes)
        slots = tuple(value)
        if len(slots) != 3:
            raise TemplateError(f"a template has three positions, got {len(slots)}")
        return cls(*slots)

    @classmethod
    def parse(cls, text: str, prefixes: PrefixMap | None = None) -> Template:
        """Parse `?s ac:battery_level "very low"`: IRIs, prefixed names, literals, `?vars`, `*`.

        Raises:
            TemplateError: not three terms, or an unknown prefix.
        """
        prefixes = prefixes or PrefixMap()
        slots: list[Slot] = []
        pos = 0
        text = text.strip()
        while pos < len(text):
            match = _TOKEN_RE.match(text, pos)
            if match is None or match.end() == pos:
                raise TemplateError(f"cannot read template {text!r} at column {pos + 1}")
            slots.append(_slot(match, prefixes, text))
            pos = match.end()
            while pos < len(text) and text[pos].isspace():
                pos += 1
        if len(slots) != 3:
            raise TemplateError(f"a template has three terms, got {len(slots)} in {text!r}")
        return cls(*slots)

    def variables(self) -> list[str]:
        """Return the names of the template's variables."""
        return [str(t) for t in self.slots() if isinstance(t, Variable)]

    def slots(self) -> tuple[Slot, Slot, Slot]:
        """Return `(s, p, o)`."""
        return (self.s, self.p, self.o)

    def pattern(self) -> tuple[Node | None, Node | None, Node | None]:
        """Return the rdflib `triples()` pattern: variables become None."""
        return tuple(None if isinstance(t, Variable) else t for t in self.slots())  # type: ignore[return-value]

    def match(self, triple: Triple) -> dict[str, Node] | None:
        """Return the variable bindings when the triple matches, else None."""
        bindings: dict[str, Node] = {}
        for slot, term in zip(self.slots(), triple, strict=True):
            if slot is None:
                continue
            if isinstance(slot, Variable):
                name = str(slot)
                if bindings.setdefault(name, term) != term:
                    return None
            elif slot != term:
                return None
        return bindings

    def to_wire(self) -> list[str | None]:
        """Return the template as three N-Triples texts or None (wildcards)."""
        return [None if t is None or isinstance(t, Variable) else to_nt(t) for t in self.slots()]

    def __str__(self) -> str:
        return " ".join("*" if t is None else t.n3() for t in self.slots())


def _position(value: object) -> Slot:
    """Return a template position as a term, a Variable or None.

    Raises:
        TemplateError: a plain string other than `?name`, or not an RDF term at all.
    """
    if value is None or isinstance(value, Node):
        return value
    if isinstance(value, str):
        if _VAR_RE.fullmatch(value):
            return Variable(value[1:])
        raise TemplateError(
            f"template position {value!r} is a plain string: give None, '?name', an rdflib "
            "URIRef or Literal, or the whole template as text (Template.parse)"
        )
    raise TemplateError(f"template position {value!r} is not an RDF term, None or '?name'")


def _slot(match: re.Match[str], prefixes: PrefixMap, text: str) -> Slot:
    kind = match.lastgroup if match.lastgroup not in ("lang", "dt") else "lit"
    token = match.group(kind)
    if kind == "iri":
        return URIRef(token[1:-1])
    if kind == "var":
        return Variable(token[1:])
    if kind == "wild":
        return None
    if kind == "num":
        datatype = XSD.integer if re.fullmatch(r"[+-]?\d+", token) else XSD.decimal
        if "e" in token.lower():
            datatype = XSD.double
        return Literal(token, datatype=datatype)
    if kind == "bnode":
        return BNode(token[2:])
    if kind == "pname":
        return RDF.type if token == "a" else _expand(token, prefixes, text)
    body = unescape(token[1:-1])
    if match.group("lang"):
        return Literal(body, lang=match.group("lang"))
    datatype = match.group("dt")
    if datatype:
        return Literal(
            body,
            datatype=URIRef(datatype[1:-1])
            if datatype[0] == "<"
            else _expand(datatype, prefixes, text),
        )
    return Literal(body)


def _expand(pname: str, prefixes: PrefixMap, text: str) -> URIRef:
    iri = prefixes.expand(pname)
    if iri is None:
        raise TemplateError(f"unknown prefix in {pname!r} (template {text!r})")
    return iri


def bindings_for(template: Template, triples: Iterable[Triple]) -> list[Mapping[str, Node]]:
    """Return the variable bindings of every triple that matches."""
    found = []
    for triple in triples:
        bound = template.match(triple)
        if bound is not None:
            found.append(bound)
    return found
