"""Jena's rule grammar over a file's tokens: one rule at a time, one token of lookahead.

The grammar (what a rule, a clause and a node are) is `parser`'s docstring. Apart
from the reader there (files, `@prefix`, `@include`, carrying on after an error)
because it sees only tokens: it knows where a rule begins and ends, and which
bracket an early end of file left open, never which file it is in.
"""

from __future__ import annotations

import re

from rdflib import BNode, Literal, URIRef

from space.reasoning.builtins import Registry
from space.reasoning.checks import located
from space.reasoning.errors import RuleError, RuleSyntaxError
from space.reasoning.recovery import Resume, resume_after
from space.reasoning.rules import Call, Functor, Item, Location, Pattern, Rule, Term, Var
from space.reasoning.tokens import Kind, Token
from space.reasoning.values import number

# A word with one of these before its colon is a full IRI when no prefix of that name is known.
_SCHEMES = ("http", "https", "urn", "file", "ftp", "mailto")
_DATATYPE_SCHEMES = ("http", "urn", "ftp", "mailto")
AT_END = "unexpected end of file"
_LANGUAGE = re.compile(r"@[A-Za-z]{1,8}(-[A-Za-z0-9]{1,8})*")


class RuleParser:
    """Read rules from tokens, one token of lookahead, as Jena's `Rule.Parser` does."""

    def __init__(
        self, tokens: list[Token], end: Location, registry: Registry, prefixes: dict[str, str]
    ) -> None:
        self.tokens = tokens
        self.position = 0
        self.end = end
        self.registry = registry
        self.prefixes = prefixes
        self.name: str | None = None
        self.opened: list[tuple[Token, str | None, bool]] = []  # token, rule name, is a rule

    def done(self) -> bool:
        return self.position >= len(self.tokens)

    def peek(self) -> Token:
        if self.done():
            raise RuleSyntaxError(self._at_end())
        return self.tokens[self.position]

    def next(self) -> Token:
        token = self.peek()
        self.position += 1
        if token.kind is Kind.UNCLOSED:
            raise self.fail(token, f"syntax error: string not closed ({token.text})")
        return token

    def resume(self, start: int) -> Resume:
        """Move past the rule that began at token `start`, after an error in it."""
        resume = resume_after(self.tokens, start)
        self.position = resume.at
        self.name = None
        self.opened.clear()
        return resume

    def fail(self, token: Token, message: str) -> RuleSyntaxError:
        return RuleSyntaxError(located(token.where, self.name, message))

    def rule(self, opening: Token | None = None) -> Rule:
        """Read one rule: `[name: ...]`, `name: ... .`, or, nested, what follows its `[`."""
        start = opening or self.peek()
        if opening is None and _is(start, Kind.SYNTAX, "["):
            self.next()
        name = None
        token = self.peek()
        if token.kind is Kind.WORD and token.text.endswith(":") and len(token.text) > 1:
            name = token.text[:-1]
            self.next()
        outer = self.name
        self.name = name or outer
        self.opened.append((start, name, True))
        body: list[Item | Rule] = []
        while not _is(self.peek(), Kind.WORD, "->", "<-"):
            body.append(self.clause())
        backward = self.next().text == "<-"
        head: list[Item | Rule] = []
        while not (_is(self.peek(), Kind.WORD, ".") or _is(self.peek(), Kind.SYNTAX, "]")):
            head.append(self.clause())
        self.next()
        self.opened.pop()
        self.name = outer
        where = start.where
        if backward:
            return Rule(name, tuple(head), tuple(body), where, backward=True)  # type: ignore[arg-type]
        return Rule(name, tuple(body), tuple(head), where)  # type: ignore[arg-type]

    def clause(self) -> Item | Rule:
        token = self.peek()
        if _is(token, Kind.SYNTAX, "("):
            nodes = self.node_list()
            if len(nodes) != 3:
                raise self.fail(token, f"a triple has 3 nodes, this one has {len(nodes)}")
            s, p, o = nodes
            return Pattern(s, p, o, token.where)
        if _is(token, Kind.SYNTAX, "["):
            return self.rule(self.next())
        if token.kind is not Kind.WORD or token.text in ("->", "<-", "."):
            raise self.fail(token, f"syntax error: unexpected {token}")
        self.next()
        builtin = self.registry.get(token.text)
        if builtin is None:
            raise RuleError(located(token.where, self.name, f"unknown builtin '{token.text}'"))
        return Call(builtin, tuple(self.node_list()), token.where)

    def node_list(self) -> list[Term]:
        opening = self.next()
        if not _is(opening, Kind.SYNTAX, "("):
            raise self.fail(opening, f"syntax error: expected '(', found {opening}")
        self.opened.append((opening, None, False))
        nodes = []
        while (token := self.next()).kind is not Kind.SYNTAX:
            nodes.append(self.node(token))
        if token.text != ")":
            raise self.fail(token, f"syntax error: unexpected {token!s}, expected ')'")
        self.opened.pop()
        return nodes

    def node(self, token: Token) -> Term:
        text = token.text
        if token.kind is Kind.STRING:
            return self.literal(token)
        if text in ("->", "<-"):
            raise self.fail(token, f"syntax error: unexpected '{text}' (a '(' is not closed)")
        if text.startswith("?"):
            return Var(text[1:])
        if text in ("*", "_"):
            raise self.fail(token, "wildcard variables are not supported (as in Jena)")
        if text.startswith("<") and text.endswith(">"):
            return URIRef(text[1:-1])
        if text.startswith("_"):
            return BNode(text[1:])
        if ":" in text:
            return URIRef(self.expand(token, text, _SCHEMES))
        if text[0].isdigit() or (text[0] == "-" and len(text) > 1 and text[1].isdigit()):
            return number(text)
        if not self.done() and _is(self.peek(), Kind.SYNTAX, "("):
            return Functor(text, tuple(self.node_list()))
        return URIRef(text)

    def literal(self, token: Token) -> Literal:
        if self.done():
            return Literal(token.text)
        after = self.peek()
        if after.kind is Kind.WORD and after.text.startswith("^^"):
            self.next()
            datatype = after.text[2:]
            if ":" in datatype:
                datatype = self.expand(after, datatype, _DATATYPE_SCHEMES)
            return Literal(token.text, datatype=URIRef(datatype))
        if after.kind is Kind.WORD and after.glued and _LANGUAGE.fullmatch(after.text):
            self.next()
            return Literal(token.text, lang=after.text[1:])
        return Literal(token.text)

    def expand(self, token: Token, text: str, schemes: tuple[str, ...]) -> str:
        prefix, _, local = text.partition(":")
        if prefix in self.prefixes:
            return self.prefixes[prefix] + local
        if prefix in schemes:
            return text
        raise RuleError(located(token.where, self.name, f"unknown prefix '{prefix}:'"))

    def _at_end(self) -> str:
        message = f"syntax error: {AT_END}"
        for opening, name, is_rule in reversed(self.opened):
            if is_rule and opening.text == "[":
                rule = f"rule '{name}'" if name else "the rule"
                message += f": expected ']' to close {rule} opened at line {opening.where.line}"
                return located(self.end, None, message)
            if not is_rule:
                message += f": expected ')' to close the '(' opened at line {opening.where.line}"
                return located(self.end, self.name, message)
        if self.opened:
            opening, name, _ = self.opened[-1]
            rule = f"rule '{name}'" if name else "the rule"
            message += f": expected '.' to end {rule} started at line {opening.where.line}"
        return located(self.end, None, message)


def _is(token: Token, kind: Kind, *texts: str) -> bool:
    return token.kind is kind and token.text in texts
