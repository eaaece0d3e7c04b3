"""Read the argument of an `@prefix` or `@include` line as Jena 4.5 does."""

from __future__ import annotations

from space.reasoning.checks import located
from space.reasoning.errors import RuleSyntaxError
from space.reasoning.tokens import Directive


def prefix_line(directive: Directive) -> tuple[str, str]:
    """Read `@prefix name: <iri>` as Jena does: a word, then the IRI (the colon optional)."""
    words = directive.rest.split(None, 1)
    if len(words) < 2:
        raise RuleSyntaxError(located(directive.where, None, "@prefix needs a name and an IRI"))
    name = words[0].removesuffix(":")
    return name, uri_argument(words[1], directive)


def ignored_text(rest: str) -> str:
    """Return what follows a directive's `<...>` other than a dot: Jena drops it unread."""
    close = rest.find(">")
    return rest[close + 1 :].strip().removeprefix(".").strip() if close >= 0 else ""


def uri_argument(rest: str, directive: Directive) -> str:
    """Return `<...>`'s content, or the trimmed rest of the line when it has no `<`."""
    token = rest.strip()
    if token.startswith("<"):
        close = token.find(">")
        if close < 0:
            message = f"{directive.keyword}: '<' without '>'"
            raise RuleSyntaxError(located(directive.where, None, message))
        return token[1:close]
    if not token:
        raise RuleSyntaxError(located(directive.where, None, f"{directive.keyword} needs an IRI"))
    return token
