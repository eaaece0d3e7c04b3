"""Format query answers for `tspace query` and `tspace take`."""

from __future__ import annotations

from typing import TextIO

from rdflib import Graph, Literal
from rdflib.query import Result

from space._display import sparql_json, table
from space.errors import InputError
from space.prefixes import PrefixMap
from space.template import Template
from space.terms import Triple


def print_graph(graph: Graph, prefixes: PrefixMap, out: TextIO) -> None:
    """Write a graph as Turtle with the space's prefixes; nothing at all for an empty graph.

    So that `tspace take` / `query -f turtle` with no match print nothing, and
    `[ -z "$(tspace take ...)" ]` tells "nothing matched" in a script.
    """
    if not len(graph):
        return
    for name, ns in prefixes.as_dict().items():
        graph.bind(name, ns, override=True)
    out.write(graph.serialize(format="turtle"))


def print_template(
    template: Template, triples: list[Triple], prefixes: PrefixMap, fmt: str, out: TextIO
) -> None:
    """Write the triples matching a template as a table of bindings, JSON results or Turtle."""
    if fmt == "turtle":
        graph = Graph()
        for t in triples:
            graph.add(t)
        print_graph(graph, prefixes, out)
        return
    names = list(dict.fromkeys(template.variables()))
    if names:
        rows = list({tuple(b[n] for n in names) for t in triples if (b := template.match(t))})
    else:
        names, rows = ["s", "p", "o"], list(triples)
    if fmt == "json":
        out.write(sparql_json(names, rows) + "\n")
    else:
        out.write(table(names, rows, prefixes, sort=True) + "\n")


def print_lifespans(
    lives: list[tuple[Triple, float | None]], prefixes: PrefixMap, fmt: str, out: TextIO
) -> None:
    """Write triples with their remaining life in seconds (`permanent` if they have none)."""
    names = ["s", "p", "o", "lifespan"]
    if fmt == "json":
        rows = [(*t, None if left is None else Literal(round(left, 3))) for t, left in lives]
        out.write(sparql_json(names, rows) + "\n")
        return
    texts = [(*t, "permanent" if left is None else f"{left:.3f}") for t, left in lives]
    out.write(table(names, texts, prefixes, sort=True) + "\n")


def print_sparql(result: Result, prefixes: PrefixMap, fmt: str, out: TextIO) -> None:
    """Write a SPARQL result as a table, SPARQL JSON results, or Turtle (CONSTRUCT).

    Raises:
        InputError: Turtle asked for a SELECT/ASK, which has no graph.
    """
    if result.type in ("CONSTRUCT", "DESCRIBE"):
        if fmt == "json":
            raise InputError("a CONSTRUCT result is a graph: use --format turtle or table")
        if fmt == "turtle" or result.graph is None:
            print_graph(result.graph or Graph(), prefixes, out)
        else:
            out.write(table(["s", "p", "o"], list(result.graph), prefixes, sort=True) + "\n")
        return
    if fmt == "turtle":
        raise InputError(f"a {result.type} result is not a graph: use --format table or json")
    if result.type == "ASK":
        if fmt == "json":
            out.write(result.serialize(format="json").decode() + "\n")
        else:
            out.write(("yes" if result.askAnswer else "no") + "\n")
        return
    names = [str(v) for v in result.vars or []]
    rows = [tuple(row[v] for v in result.vars or []) for row in result]
    if fmt == "json":
        out.write(sparql_json(names, rows) + "\n")
    else:
        out.write(table(names, rows, prefixes) + "\n")
