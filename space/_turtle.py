"""Read Turtle documents given by the user, with errors that name the line."""

from __future__ import annotations

import sys
from pathlib import Path

from rdflib import Graph

from space.errors import InputError


def read_turtle(source: str) -> Graph:
    """Parse a Turtle file (or `-` for standard input) into a graph.

    Raises:
        InputError: the file is missing or not valid Turtle (the message has the line).
    """
    name = "<stdin>" if source == "-" else source
    try:
        text = sys.stdin.read() if source == "-" else Path(source).read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(f"{name}: {exc.strerror}") from exc
    return parse_turtle(text, name)


def parse_turtle(text: str, name: str = "<string>") -> Graph:
    """Parse Turtle text; see `read_turtle`."""
    graph = Graph()
    try:
        graph.parse(data=text, format="turtle")
    except Exception as exc:  # rdflib's parser raises BadSyntax and assorted others
        raise InputError(f"{name}: bad Turtle: {_one_line(exc)}") from exc
    return graph


def _one_line(exc: Exception) -> str:
    lines = getattr(exc, "lines", None)
    message = getattr(exc, "_why", None) or str(exc)
    message = " ".join(message.split())
    return f"line {lines + 1}: {message}" if isinstance(lines, int) else message
