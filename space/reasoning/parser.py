"""Parse Jena rules files into `Rule`s, with `file:line:column` in every error.

Prefixes rdf, rdfs, owl and xsd are known; `@prefix` adds more from where it is
written; `@include <path>` reads another file relative to the including one,
which starts with the includer's prefixes.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from decimal import Decimal
from functools import cache
from pathlib import Path

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from rdflib import OWL, RDF, RDFS, XSD, Literal, URIRef

from space.reasoning.builtins import Registry
from space.reasoning.checks import check_names, check_rule, located
from space.reasoning.errors import RuleError, RuleSyntaxError, unreadable
from space.reasoning.rules import Call, Functor, Item, Location, Pattern, Rule, Term, Var
from space.terms import unescape

DEFAULT_PREFIXES = {"rdf": str(RDF), "rdfs": str(RDFS), "owl": str(OWL), "xsd": str(XSD)}


@cache
def _grammar() -> Lark:
    text = (Path(__file__).parent / "jena.lark").read_text()
    return Lark(text, parser="lalr", propagate_positions=True)


def parse_rules(
    text: str,
    registry: Registry,
    *,
    source: str = "<string>",
    prefixes: dict[str, str] | None = None,
) -> list[Rule]:
    """Parse the text of a rules file; `@include` paths resolve against `source`'s folder.

    Raises:
        RuleSyntaxError: the text is not valid Jena rule syntax, or an include is missing.
        RuleError: a rule uses an unknown builtin, a wrong arity, a bad drop/remove index
            or a head variable the body does not bind; two rules (includes counted) share
            a name.
    """
    rules = list(_Reader(registry, ()).read(text, source, dict(prefixes or DEFAULT_PREFIXES)))
    check_names(rules)
    return rules


def load_rules(paths: Iterable[str | Path], registry: Registry) -> list[Rule]:
    """Parse rules files in order, their includes in place.

    Raises:
        RuleSyntaxError, RuleError: as `parse_rules`; a missing file is a RuleSyntaxError.
    """
    reader = _Reader(registry, ())
    rules = [rule for path in paths for rule in reader.read_file(Path(path), DEFAULT_PREFIXES)]
    check_names(rules)
    return rules


class _Reader:
    """Turn parse trees into rules, following includes (and refusing include cycles)."""

    def __init__(self, registry: Registry, including: tuple[Path, ...]) -> None:
        self.registry = registry
        self.including = including

    def read_file(
        self, path: Path, prefixes: dict[str, str], where: Location | None = None
    ) -> Iterator[Rule]:
        resolved = path.resolve()
        if resolved in self.including:
            raise RuleSyntaxError(located(where, None, f"include cycle through {path}"))
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            message = unreadable(path, exc)
            raise RuleSyntaxError(
                located(where, None, f"cannot include {message}" if where else message)
            ) from exc
        except UnicodeDecodeError as exc:
            raise RuleSyntaxError(located(where, None, f"{path}: not UTF-8 text")) from exc
        inner = _Reader(self.registry, (*self.including, resolved))
        yield from inner.read(text, str(path), dict(prefixes))

    def read(self, text: str, source: str, prefixes: dict[str, str]) -> Iterator[Rule]:
        try:
            tree = _grammar().parse(text)
        except UnexpectedInput as exc:
            raise RuleSyntaxError(_syntax_message(exc, text, source)) from None
        for statement in tree.children:
            assert isinstance(statement, Tree)
            where = Location(source, statement.meta.line, statement.meta.column)
            if statement.data == "prefix":
                name, iri = statement.children
                prefixes[str(name)[:-1]] = str(iri)[1:-1]
            elif statement.data == "include":
                target = Path(str(statement.children[0])[1:-1])
                if not target.is_absolute():
                    target = Path(source).parent / target
                yield from self.read_file(target, prefixes, where)
            else:
                yield _RuleBuilder(self.registry, prefixes, source).rule(statement, where)


class _RuleBuilder:
    """Build one rule from its parse tree, resolving prefixes and builtins."""

    def __init__(self, registry: Registry, prefixes: dict[str, str], source: str) -> None:
        self.registry = registry
        self.prefixes = prefixes
        self.source = source
        self.name: str | None = None

    def rule(self, tree: Tree, where: Location) -> Rule:
        name_token, body_tree, arrow, head_tree = tree.children
        self.name = str(name_token)[:-1] if name_token is not None else None
        if str(arrow) == "<-":
            raise RuleError(located(where, self.name, "backward rules (<-) are not supported"))
        body = self.items(body_tree)
        head = self.items(head_tree)
        rule = Rule(self.name, tuple(body), tuple(head), where)
        check_rule(rule)
        return rule

    def here(self, node: Tree | Token) -> Location:
        if isinstance(node, Token):
            return Location(self.source, node.line or 0, node.column or 0)
        return Location(self.source, node.meta.line, node.meta.column)

    def fail(self, node: Tree | Token, message: str) -> RuleError:
        return RuleError(located(self.here(node), self.name, message))

    def items(self, tree: Tree) -> list[Item]:
        items: list[Item] = []
        for child in tree.children:
            assert isinstance(child, Tree)
            if child.data == "triple":
                s, p, o = (self.term(c) for c in child.children)
                items.append(Pattern(s, p, o, self.here(child)))
            elif child.data == "call":
                name, *args = child.children
                builtin = self.registry.get(str(name))
                if builtin is None:
                    raise self.fail(child, f"unknown builtin '{name}'")
                terms = tuple(self.term(a) for a in args if a is not None)
                items.append(Call(builtin, terms, self.here(child)))
            else:
                raise self.fail(child, "nested (backward) rules are not supported")
        return items

    def term(self, node: Tree | Token) -> Term:
        if isinstance(node, Token):
            raise self.fail(node, f"unexpected {node}")
        first = node.children[0] if node.children else None
        kind = node.data
        if kind == "var":
            return Var(str(first)[1:])
        if kind == "iri":
            return URIRef(str(first)[1:-1])
        if kind == "pname":
            return self.expand(first)  # type: ignore[arg-type]
        if kind == "number":
            return _number(str(first))
        if kind == "literal":
            return self.literal(node)
        name, *args = node.children
        return Functor(str(name), tuple(self.term(a) for a in args if a is not None))

    def expand(self, token: Token) -> URIRef:
        prefix, _, local = str(token).partition(":")
        if prefix not in self.prefixes:
            raise self.fail(token, f"unknown prefix '{prefix}:'")
        return URIRef(self.prefixes[prefix] + local)

    def literal(self, node: Tree) -> Literal:
        text, suffix = node.children
        value = unescape(str(text)[1:-1])
        if suffix is None:
            return Literal(value)
        if str(suffix).startswith("@"):
            return Literal(value, lang=str(suffix)[1:])
        if str(suffix).startswith("<"):
            return Literal(value, datatype=URIRef(str(suffix)[1:-1]))
        return Literal(value, datatype=self.expand(suffix))  # type: ignore[arg-type]


def _number(text: str) -> Literal:
    """Type a bare number as Turtle does: integer, decimal or double."""
    if "e" in text.lower():
        return Literal(float(text))
    if "." in text:
        return Literal(Decimal(text))
    return Literal(int(text))


def _syntax_message(exc: UnexpectedInput, text: str, source: str) -> str:
    """Say where parsing stopped, what was there, and in which rule."""
    opened = _open_brackets(text)
    rules = [o for o in opened if o.bracket == "["]
    name = rules[-1].name if rules else None
    if isinstance(exc, UnexpectedToken) and exc.token.type == "$END":
        # LALR reports the end as a token placed on the last real one: say where the text ends.
        where = Location(source, text.count("\n") + 1, len(text) - text.rfind("\n"))
        message = "syntax error: unexpected end of file"
        if opened and opened[-1].bracket == "[":
            rule = f"rule '{name}'" if name else "the rule"
            message += f": expected ']' to close {rule} opened at line {opened[-1].line}"
            return located(where, None, message)
        if opened:
            message += f": expected ')' to close the '(' opened at line {opened[-1].line}"
        return located(where, name, message)
    if isinstance(exc, UnexpectedToken):
        found = repr(str(exc.token))
    elif isinstance(exc, UnexpectedCharacters):
        found = repr(text[exc.pos_in_stream]) if exc.pos_in_stream is not None else "input"
    else:
        found = "input"
    where = Location(source, exc.line, exc.column)
    return located(where, name, f"syntax error: unexpected {found}")


@dataclass
class _Opened:
    """A `[` or `(` not closed yet, and the name of the rule a `[` starts."""

    bracket: str
    line: int
    name: str | None = None


def _open_brackets(text: str) -> list[_Opened]:
    """Return the brackets still open where parsing stops, outermost first."""
    opened: list[_Opened] = []
    parser = _grammar().parse_interactive(text)
    try:
        for token in parser.lexer_thread.lex(parser.parser_state):
            parser.feed_token(token)  # first, so that the token that fails does not count
            if token.type in ("LSQB", "LPAR"):
                opened.append(_Opened(str(token), token.line or 0))
            elif token.type in ("RSQB", "RPAR") and opened:
                opened.pop()
            elif token.type == "RULENAME" and opened:
                opened[-1].name = str(token)[:-1]
    except UnexpectedInput:
        pass  # the error being explained: `opened` is the state just before it
    return opened
