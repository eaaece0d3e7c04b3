"""`tspace watch`: print every change that matches a template, until Ctrl-C."""

from __future__ import annotations

import argparse
import queue
import sys

from space.cli.options import add_connect, open_space

ORDER = 50


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `watch` sub-command."""
    p = sub.add_parser(
        "watch",
        help="print changes as they happen",
        description="Print each change matching TEMPLATE (default: all) as '+ s p o' and "
        "'- s p o' lines, '[inferred]' marking the inferred graph, until Ctrl-C.",
    )
    p.add_argument("template", nargs="?", metavar="TEMPLATE", help="e.g. '?s ac:battery_level ?o'")
    add_connect(p, space=None)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Subscribe and print lines from the main thread (flushed, so pipes see them at once)."""
    from space._display import triple_text
    from space._subscription import Change

    lines: queue.SimpleQueue[Change] = queue.SimpleQueue()
    with open_space(args, agent="tspace-watch") as ts:
        prefixes = ts.load_prefixes(timeout=args.timeout)
        ts.subscribe(args.template, lines.put, timeout=args.timeout)
        while True:
            change = lines.get()
            prefixes.update(change.prefixes)
            for sign, tag, triples in (
                ("-", "", change.removed),
                ("-", " [inferred]", change.inferred_removed),
                ("+", "", change.added),
                ("+", " [inferred]", change.inferred_added),
            ):
                for t in triples:
                    print(f"{sign} {triple_text(t, prefixes)}{tag}", file=sys.stdout, flush=True)
