"""`tspace take`: remove the triples matching a template and print them."""

from __future__ import annotations

import argparse
import sys

from space.cli.options import add_connect, open_space

ORDER = 55


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `take` sub-command."""
    p = sub.add_parser(
        "take",
        help="remove and print the triples matching a template",
        description="Atomically read and remove the asserted triples matching TEMPLATE; "
        "print them as Turtle. Nothing matched: prints nothing and exits 0.",
    )
    p.add_argument("template", metavar="TEMPLATE", help="e.g. '?s ac:requested_task ?t'")
    add_connect(p, space=None)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Take and print."""
    from space.cli.results import print_graph
    from space.template import Template

    with open_space(args, agent="tspace-take") as ts:
        prefixes = ts.load_prefixes(timeout=args.timeout)
        graph = ts.take(Template.parse(args.template, prefixes), timeout=args.timeout)
        print_graph(graph, prefixes, sys.stdout)
    return 0
