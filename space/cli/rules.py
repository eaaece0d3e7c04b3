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
    """Print each file's rules, or every error in it on stderr; return 1 if any file has one.

    Each error is one line, `file:line:column: ...`; after an error the checker reads on
    from the end of the broken rule, so one run lists them all.
    """
    from space.reasoning import RuleError, build_engine, default_registry
    from space.reasoning.parser import check_rules
    from space.reasoning.rules import Call

    registry = default_registry()
    errors = failed = 0
    for path in args.files:
        rules, found = check_rules([path], registry, warn=_warn)
        if not found and not rules:  # an empty file (or one of comments) is a mistake
            found = [f"{path}: no rules in it"]
        elif not found:
            try:
                build_engine(rules, owl=False, registry=registry)  # what only compiling finds
            except RuleError as exc:
                found = [exc]
        for error in found:
            print(error, file=sys.stderr)
        if found:
            errors += len(found)
            failed += 1
            continue
        print(f"{path}: {len(rules)} rule{'' if len(rules) == 1 else 's'}")
        for rule in rules:
            calls = [i for i in (*rule.body, *rule.head) if isinstance(i, Call)]
            kind = "production" if any(not c.builtin.monotonic for c in calls) else "monotonic"
            kind = f"backward, {kind}" if rule.backward else kind
            print(f"  {rule.where}  {rule.label}  ({kind})")
    if errors > 1:
        print(
            f"tspace rules: {errors} errors in {failed} file{'s' if failed > 1 else ''}",
            file=sys.stderr,
        )
    return 1 if failed else 0


def _warn(message: str) -> None:
    print(f"tspace rules: warning: {message}", file=sys.stderr)
