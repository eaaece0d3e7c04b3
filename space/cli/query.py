"""`tspace query`: SPARQL or a triple template, printed as a table, JSON or Turtle."""

from __future__ import annotations

import argparse
import sys

from space.cli.options import add_connect, open_space
from space.errors import UsageError

ORDER = 40
FORMATS = ("table", "json", "turtle")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `query` sub-command."""
    p = sub.add_parser(
        "query",
        help="query the space with SPARQL or a triple template",
        description="Run a SPARQL SELECT/ASK/CONSTRUCT, or match a template such as "
        "'?s ac:battery_level ?o' (prefixes: those registered in the space). "
        "No match: a table prints its header only, Turtle prints nothing; exit 0 either way.",
    )
    p.add_argument("sparql", nargs="?", metavar="SPARQL", help="SPARQL query text (- for stdin)")
    p.add_argument("--template", "-t", metavar="TEMPLATE", help="a triple template instead")
    p.add_argument(
        "--format", "-f", choices=FORMATS, default="table", help="output (default table)"
    )
    p.add_argument(
        "--graph",
        choices=("all", "asserted", "inferred"),
        default="all",
        help="for templates: which graph (default all)",
    )
    p.add_argument(
        "--stale",
        action="store_true",
        help="cluster mode: answer from this replica even without a quorum (possibly behind) "
        "instead of failing with 'no quorum'",
    )
    p.add_argument(
        "--with-lifespan",
        action="store_true",
        help="for templates: asserted triples only, with the seconds each has left to live",
    )
    add_connect(p, space=None)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Ask the store and print the answer on stdout."""
    from space.cli.results import print_lifespans, print_sparql, print_template

    if (args.sparql is None) == (args.template is None):
        raise UsageError("give either SPARQL text or --template")
    if args.with_lifespan and (args.template is None or args.format == "turtle"):
        raise UsageError("--with-lifespan goes with --template, as a table or JSON")
    with open_space(args, agent="tspace-query") as ts:
        ts.stale = args.stale
        prefixes = ts.load_prefixes(timeout=args.timeout)
        if args.template is not None:
            from space.template import Template

            template = Template.parse(args.template, prefixes)
            if args.with_lifespan:
                lives = ts.lifespans(template, timeout=args.timeout)
                print_lifespans(lives, prefixes, args.format, sys.stdout)
                return 0
            triples = ts.match(template, graph=args.graph, timeout=args.timeout)
            print_template(template, triples, prefixes, args.format, sys.stdout)
        else:
            text = sys.stdin.read() if args.sparql == "-" else args.sparql
            result = ts.query_sparql(text, timeout=args.timeout)
            print_sparql(result, prefixes, args.format, sys.stdout)
    return 0
