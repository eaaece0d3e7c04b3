"""Split a Jena rules file into directives and tokens exactly as Jena 4.5 does, with positions.

Jena reads a rules file line by line: a line whose first character is `#`, or
that starts with `//` once trimmed, is a comment; a line starting with
`@prefix` or `@include` is a directive (the whole line); every other line goes
to a tokenizer that splits on `()[], ` and whitespace and reads quoted strings
(a backslash takes the next character as it is). So `#` inside a word is not a
comment (`galen:#Neonate` and a bare `http://x#y` are one token each), and a
token is any run of other characters (`->`, `.`, `ex:a`, `?x`, `42`).

Beyond Jena, which rejects such files: a word starting with `#` or `//` after
other text on a line starts a comment to the end of the line, and `->` glued to
the next word (`)->drop(6)`) is the arrow. Tokens carry their line and column.
"""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import Enum

from space.reasoning.rules import Location

_TRIM = "".join(chr(c) for c in range(33))  # what Java's String.trim removes
_SYNTAX = "()[]"
_SEPARATORS = ", \t\n\r"
_QUOTES = "'\""
_ARROWS = ("->", "<-")


class Kind(Enum):
    """What a token is."""

    SYNTAX = "syntax"  # ( ) [ ]
    WORD = "word"  # anything between delimiters
    STRING = "string"  # the text of a quoted string, quotes and escapes removed
    UNCLOSED = "unclosed"  # a quote with no closing quote: an error once the parser reaches it


@dataclass(frozen=True)
class Token:
    """One token and where it starts; `glued` says it follows the previous one with no gap."""

    kind: Kind
    text: str
    where: Location
    glued: bool = False

    def __str__(self) -> str:
        return repr(self.text) if self.kind is Kind.STRING else self.text


@dataclass(frozen=True)
class Directive:
    """An `@prefix` or `@include` line: the keyword and the rest of the line."""

    keyword: str
    rest: str
    where: Location


@dataclass
class Lexed:
    """A file split into its directives (in order) and the tokens of its rule text."""

    directives: list[Directive]
    tokens: list[Token]
    end: Location


def lex(text: str, source: str) -> Lexed:
    """Split `text` into directives and tokens (an unclosed quote ends them, as an UNCLOSED)."""
    directives: list[Directive] = []
    body: list[str] = []
    starts: list[int] = []  # offset in the joined rule text where each kept line starts
    places: list[tuple[int, int]] = []  # (line number, column of its first kept character)
    offset = 0
    lines = text.splitlines()
    for number, line in enumerate(lines, 1):
        if line.startswith("#"):
            continue
        trimmed = line.strip(_TRIM)
        lead = len(line) - len(line.lstrip(_TRIM))
        if trimmed.startswith("//"):
            continue
        for keyword in ("@prefix", "@include"):
            if trimmed.startswith(keyword):
                where = Location(source, number, lead + 1)
                directives.append(Directive(keyword, trimmed[len(keyword) :], where))
                break
        else:
            starts.append(offset)
            places.append((number, lead + 1))
            body.append(trimmed + "\n")
            offset += len(trimmed) + 1
    joined = "".join(body)

    def where(at: int) -> Location:
        if not starts:
            return Location(source, 1, 1)
        i = bisect_right(starts, at) - 1
        line, column = places[i]
        return Location(source, line, column + at - starts[i])

    end = Location(source, text.count("\n") + 1, len(text) - text.rfind("\n"))
    return Lexed(directives, list(_tokens(joined, where, end)), end)


def _tokens(text: str, where: Callable[[int], Location], end: Location) -> Iterator[Token]:
    p, n = 0, len(text)
    last_end = -1
    while p < n:
        c = text[p]
        if c in _SEPARATORS:
            p += 1
            continue
        glued = p == last_end
        if c in _SYNTAX:
            yield Token(Kind.SYNTAX, c, where(p), glued)
            p += 1
        elif c in _QUOTES:
            start = p
            p += 1
            chars = []
            while p < n and text[p] != c:
                if text[p] == "\\":
                    p += 1
                    if p >= n:
                        break
                chars.append(text[p])
                p += 1
            if p >= n:
                yield Token(Kind.UNCLOSED, c, where(start), glued)
                return
            p += 1
            yield Token(Kind.STRING, "".join(chars), where(start), glued)
        elif text.startswith(("#", "//"), p) and (p == 0 or text[p - 1] in _SEPARATORS):
            p = text.find("\n", p)  # beyond Jena: a comment after text on a line
            p = n if p < 0 else p
        else:
            start = p
            while p < n and text[p] not in _SYNTAX and text[p] not in _SEPARATORS:
                p += 1
            word = text[start:p]
            if len(word) > 2 and word[:2] in _ARROWS:  # beyond Jena: `)->drop(6)`
                yield Token(Kind.WORD, word[:2], where(start), glued)
                start, word, glued = start + 2, word[2:], True
            yield Token(Kind.WORD, word, where(start), glued)
        last_end = p
