"""Read Turtle documents given by the user, with one-line errors that name the file and line.

A UTF-8 byte-order mark is accepted (editors on Windows write one); a binary
file, text that is not UTF-8, and a literal whose text does not fit its
datatype (`"abc"^^xsd:integer`) are refused, each in one line, instead of
rdflib's tracebacks.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from rdflib import Graph, Literal

from space.errors import InputError


def read_turtle(source: str, base: str | None = None) -> Graph:
    """Parse a Turtle file (or `-` for standard input) into a graph.

    `base` resolves relative IRIs (rdflib's default when None).

    Raises:
        InputError: the file is missing, binary, not UTF-8, or not valid Turtle
            (the message has the file and line).
    """
    name = "<stdin>" if source == "-" else source
    try:
        data = sys.stdin.buffer.read() if source == "-" else Path(source).read_bytes()
    except OSError as exc:
        raise InputError(f"{name}: {exc.strerror}") from exc
    if b"\x00" in data[:8192]:
        raise InputError(f"{name}: a binary file, not Turtle text")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise InputError(f"{name}: line {line}: not UTF-8 text (byte {exc.start})") from exc
    return parse_turtle(text, name, base)


def parse_turtle(text: str, name: str = "<string>", base: str | None = None) -> Graph:
    """Parse Turtle text; see `read_turtle`."""
    graph = Graph()
    try:
        with _quiet("rdflib.term"):
            graph.parse(data=text.removeprefix("\ufeff"), format="turtle", publicID=base)
    except Exception as exc:  # rdflib's parser raises BadSyntax and assorted others
        raise InputError(f"{name}: bad Turtle: {_one_line(exc)}") from exc
    for _s, _p, o in graph:
        if isinstance(o, Literal) and o.ill_typed:
            where = _line_of(text, str(o))
            raise InputError(
                f"{name}: {where}literal {str(o)!r} is not a valid {_short(o.datatype)}"
            )
    return graph


@contextmanager
def _quiet(logger: str) -> Iterator[None]:
    """Silence a logger (rdflib logs a traceback per ill-typed literal; we say it in one line)."""
    log = logging.getLogger(logger)
    before = log.disabled
    log.disabled = True
    try:
        yield
    finally:
        log.disabled = before


def _line_of(text: str, lexical: str) -> str:
    index = text.find(f'"{lexical}"')
    return f"line {text.count(chr(10), 0, index) + 1}: " if index >= 0 else ""


def _short(datatype: object) -> str:
    text = str(datatype)
    xsd = "http://www.w3.org/2001/XMLSchema#"
    return f"xsd:{text[len(xsd) :]}" if text.startswith(xsd) else f"<{text}>"


def _one_line(exc: Exception) -> str:
    lines = getattr(exc, "lines", None)
    message = getattr(exc, "_why", None) or str(exc)
    message = " ".join(message.split())
    return f"line {lines + 1}: {message}" if isinstance(lines, int) else message
