"""`tspace why`: why a triple holds, as a tree down to what agents wrote."""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import TYPE_CHECKING, TextIO

from space.cli.options import add_connect, open_space
from space.explanation import ASSERTED, Explanation
from space.prefixes import PrefixMap
from space.terms import Triple

if TYPE_CHECKING:
    from space.client import TripleSpace

ORDER = 45
FORMATS = ("text", "json")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `why` sub-command."""
    p = sub.add_parser(
        "why",
        help="explain why a triple holds (the rules and facts behind it)",
        description="Ask the space's reasoner why each triple matching TRIPLE holds: the rule "
        "that concluded it (its name, file:line and the comment above it), the facts it "
        "matched, explained in turn, down to the facts agents wrote, with who wrote them "
        "and when. TRIPLE is a triple or a template such as 'ac:robot1_base ac:motion_speed "
        "?speed' (prefixes: those registered in the space). Exit 1 if nothing matching "
        "holds or no reasoner answers.",
    )
    p.add_argument(
        "triple", metavar="TRIPLE", help="a triple or template, e.g. '?d ac:running_mode ?m'"
    )
    p.add_argument("--format", "-f", choices=FORMATS, default="text", help="output (default text)")
    p.add_argument(
        "--limit", type=int, default=20, metavar="N", help="explain at most N triples (default 20)"
    )
    p.add_argument(
        "--with-lifespan",
        action="store_true",
        help="under each fact an agent wrote, the seconds it has left to live (or permanent)",
    )
    add_connect(p, space=None)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Ask the reasoner and print the trees on stdout."""
    from space.template import Template

    with open_space(args, agent="tspace-why") as ts:
        prefixes = ts.load_prefixes(timeout=args.timeout)
        template = Template.parse(args.triple, prefixes)
        trees = ts.why(template, limit=args.limit, timeout=args.timeout)
        lives = remaining_lives(ts, trees, args.timeout) if args.with_lifespan else None
    if args.format == "json":
        from space._display import triple_text

        def text(triple: Triple) -> str:
            return triple_text(triple, prefixes)

        out = [t.to_json(text) for t in trees]
        if lives is not None:
            for tree, data in zip(trees, out, strict=True):
                _json_lives(tree, data, lives)
        json.dump(out, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        for i, tree in enumerate(trees):
            if i:
                sys.stdout.write("\n")
            print_tree(tree, prefixes, sys.stdout, lives)
    if not trees:
        print(f"tspace why: nothing matching {args.triple!r} holds", file=sys.stderr)
        return 1
    return 0


Lives = dict[Triple, float | None]  # asserted triple -> seconds left (None: permanent)


def remaining_lives(ts: TripleSpace, trees: list[Explanation], timeout: float) -> Lives:
    """Ask the store the remaining life of every asserted fact of the trees (one query each).

    A fact missing from the answer no longer holds (it expired since the reasoner answered).
    """
    lives: Lives = {}
    for tree in trees:
        for _, node in tree.walk():
            if node.holds == ASSERTED and node.triple not in lives:
                found = dict(ts.lifespans(node.triple, timeout=timeout))
                lives[node.triple] = found.get(node.triple, _GONE)
    return lives


_GONE = -1.0  # in `Lives`: the fact no longer holds


def print_tree(
    tree: Explanation, prefixes: PrefixMap, out: TextIO, lives: Lives | None = None
) -> None:
    """Write one explanation as an indented tree, one fact per branch.

    With `lives` (`remaining_lives`), each fact an agent wrote says how long it has
    left, and a concluded root says when the first fact under it expires.
    """
    _node(tree, prefixes, out, "", "", "", lives)
    left = [lives.get(n.triple) for _, n in tree.walk()] if lives and tree.premises else []
    first = min((x for x in left if x is not None and x >= 0), default=None)
    if first is not None:
        if tree.holds == ASSERTED:  # a production rule's conclusion outlives its premises
            out.write(
                f"   concluded from a fact that expires in {first:.1f} s; stays until changed\n"
            )
        else:
            out.write(f"   goes when its support does: a fact under it expires in {first:.1f} s\n")


def _node(
    node: Explanation,
    prefixes: PrefixMap,
    out: TextIO,
    lead: str,
    branch: str,
    under: str,
    lives: Lives | None,
) -> None:
    from space._display import triple_text

    out.write(f"{lead}{branch}{triple_text(node.triple, prefixes)}\n")
    detail = lead + under + ("│  " if node.premises else "   ")
    lines = details(node)
    if lives is not None and node.triple in lives and not node.repeated:
        lines.append(_life(lives[node.triple]))
    for line in lines:
        out.write(f"{detail}{line}\n".replace("   \n", "\n"))
    for i, premise in enumerate(node.premises):
        last = i == len(node.premises) - 1
        _node(
            premise,
            prefixes,
            out,
            lead + under,
            "└─ " if last else "├─ ",
            "   " if last else "│  ",
            lives,
        )


def _life(left: float | None) -> str:
    if left is None:
        return "permanent"
    if left < 0:
        return "no longer holds (expired or removed since)"
    return f"expires in {left:.1f} s unless written again"


def _json_lives(node: Explanation, data: dict, lives: Lives) -> None:
    """Add `lifespan` (seconds left, null: permanent) to each asserted fact of a JSON tree.

    A fact gone since the reasoner answered gets `still_holds: false` as well.
    """
    if node.triple in lives:
        left = lives[node.triple]
        data["lifespan"] = left if left is None else max(left, 0.0)
        if left is not None and left < 0:
            data["still_holds"] = False
    for premise, sub in zip(node.premises, data["premises"], strict=True):
        _json_lives(premise, sub, lives)


def details(node: Explanation) -> list[str]:
    """Return the lines under a fact: its rule and the rule's comment, who wrote it."""
    lines = []
    if node.holds == "gone":
        lines.append("held when the rule fired; no longer holds (replaced since)")
    elif node.repeated:
        lines.append("(explained above)")
    elif node.rule is not None:
        kind = "production rule" if node.holds == "asserted" else "rule"
        where = f" ({_short(node.where)})" if node.where else ""
        lines.append(f"by {kind} {node.rule}{where}")
        if node.comment:
            lines.append(f"  “{node.comment}”")
    if node.written is not None:
        lines.append(f"written by {node.written.agent}{_when(node)}")
    elif node.holds == "asserted" and node.rule is None and not node.repeated:
        lines.append("written before the store's log begins")
    return lines


def _when(node: Explanation) -> str:
    written = node.written
    assert written is not None
    when = written.time
    text = f" at {when:%Y-%m-%d %H:%M:%S}.{when.microsecond // 1000:03d} UTC" if when else ""
    return text + (f" (changeset #{written.seq})" if written.seq else "")


def _short(where: str) -> str:
    """Return `file:line` with the file relative to the current directory when inside it."""
    path, _, line = where.rpartition(":")
    relative = os.path.relpath(path) if os.path.isabs(path) else path
    return f"{path if relative.startswith('..') else relative}:{line}"
