"""`tspace rules check FILE...`: parse rules files and list their rules, or say what is wrong."""

from __future__ import annotations

import argparse
import sys

ORDER = 60


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `rules` sub-command."""
    p = sub.add_parser(
        "rules",
        help="check Jena rules files",
        description="Check rules files (with their @include files): syntax, builtins, arities, "
        "drop/remove indices and head variables, and that the engine (the reasoner's, with "
        "backward and nested rules) can run every rule. Lists the rules when all is well.",
    )
    actions = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    check = actions.add_parser("check", help="check rules files and list their rules")
    check.add_argument("files", nargs="+", metavar="FILE", help="rules files")
    check.set_defaults(func=run_check)


def run_check(args: argparse.Namespace) -> int:
    """Print each file's rules, or its error on stderr; return 1 if any file has an error."""
    from space.reasoning import RuleError, build_engine, default_registry, load_rules
    from space.reasoning.rules import Call

    registry = default_registry()
    failed = 0
    for path in args.files:
        try:
            rules = load_rules([path], registry, warn=_warn)
            build_engine(rules, owl=False, registry=registry)  # what only compiling finds
        except RuleError as exc:
            print(exc, file=sys.stderr)
            failed += 1
            continue
        if not rules:  # an empty file (or one of comments) is a mistake, not a rule base
            print(f"{path}: no rules in it", file=sys.stderr)
            failed += 1
            continue
        print(f"{path}: {len(rules)} rule{'' if len(rules) == 1 else 's'}")
        for rule in rules:
            calls = [i for i in (*rule.body, *rule.head) if isinstance(i, Call)]
            kind = "production" if any(not c.builtin.monotonic for c in calls) else "monotonic"
            kind = f"backward, {kind}" if rule.backward else kind
            print(f"  {rule.where}  {rule.label}  ({kind})")
    return 1 if failed else 0


def _warn(message: str) -> None:
    print(f"tspace rules: warning: {message}", file=sys.stderr)
