"""Build and match strings: `strConcat uriConcat regex`."""

from __future__ import annotations

import re
from collections.abc import Callable
from functools import lru_cache

from rdflib import Literal, URIRef
from rdflib.term import Node

from space.reasoning.builtins.base import Args, Builtin, Context
from space.reasoning.builtins.javaregex import JavaRegexError, translate


def _lexical(ctx: Context, i: int | None) -> str | None:
    term = ctx.terms.term(i) if i is not None else None
    return str(term) if isinstance(term, Node) else None


def _bind_last(ctx: Context, args: Args, result: Node) -> Args | None:
    out = ctx.terms.id(result)
    if args[-1] is None:
        return (*args[:-1], out)
    return args if args[-1] == out else None


class _Concat(Builtin):
    """Bind the last argument to `make` of the lexical forms of the others, joined."""

    arity = (1, None)
    make: Callable[[str], Node]

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({nargs - 1})

    def run(self, ctx: Context, args: Args) -> Args | None:
        parts = [_lexical(ctx, i) for i in args[:-1]]
        if None in parts:
            return None
        return _bind_last(ctx, args, type(self).make("".join(parts)))  # type: ignore[arg-type]


class StrConcat(_Concat):
    """Bind the last argument to a plain literal joining the lexical forms of the others."""

    name = "strConcat"
    make = Literal


class UriConcat(_Concat):
    """Bind the last argument to the IRI joining the lexical forms of the others."""

    name = "uriConcat"
    make = URIRef


@lru_cache(maxsize=256)
def _compiled(pattern: str) -> re.Pattern[str] | None:
    try:
        return translate(pattern)
    except JavaRegexError:
        return None  # a pattern only known when the rule fires; a constant one is checked on load


class Regex(Builtin):
    """Accept when the whole text matches the pattern; bind later arguments to its groups."""

    name = "regex"
    arity = (2, None)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset(range(2, nargs))

    def check(self, args: tuple[object, ...]) -> str | None:
        pattern = args[1] if len(args) > 1 else None
        if isinstance(pattern, Literal):
            try:
                translate(str(pattern))
            except JavaRegexError as exc:
                return str(exc)
        return None

    def run(self, ctx: Context, args: Args) -> Args | None:
        text, pattern = _lexical(ctx, args[0]), _lexical(ctx, args[1])
        regex = _compiled(pattern) if pattern is not None else None
        match = regex.fullmatch(text) if regex is not None and text is not None else None
        if match is None or len(args) - 2 > len(match.groups()):
            return None
        bound = list(args)
        for position, group in enumerate(match.groups()[: len(args) - 2], start=2):
            value = ctx.terms.id(Literal(group or ""))
            if bound[position] is None:
                bound[position] = value
            elif bound[position] != value:
                return None
        return tuple(bound)


BUILTINS: tuple[Builtin, ...] = (StrConcat(), UriConcat(), Regex())
