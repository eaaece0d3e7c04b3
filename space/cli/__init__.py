"""The `tspace` command line: one sub-module per sub-command.

Each sub-module that defines `register(subparsers)` is a sub-command: it adds
its parser and sets `func` to a callable taking the parsed namespace and
returning an exit code. `ORDER` (an int) places it in `tspace --help`.
Sub-modules import their heavy dependencies inside that callable so that
`tspace --help` stays fast.

The library's own commands are the modules of this package; an application adds
its commands (the robot's `tspace up`, `tspace agent`) as modules of the same
shape, named by entry points in the `tspace.commands` group.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.metadata
import logging
import pkgutil
import sys
from types import ModuleType

from space.errors import SpaceError, UsageError


def build_parser() -> argparse.ArgumentParser:
    """Return the parser for every sub-command."""
    parser = argparse.ArgumentParser(
        prog="tspace",
        description="A distributed triple space on Eclipse Zenoh for self-configuring robots.",
        epilog="Start a robot: tspace up. Start it over from its launch file's state: "
        "tspace up --fresh. Help on a command: tspace COMMAND --help.",
    )
    parser.add_argument(
        "-v", "--verbose", action="count", default=0, help="more log output (-vv for debug)"
    )
    parser.add_argument("--version", action="version", version=f"tspace {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    modules = [
        importlib.import_module(f"{__name__}.{info.name}")
        for info in pkgutil.iter_modules(__path__)
        if not info.name.startswith("_")
    ]
    modules += plugged_commands()
    commands = [m for m in modules if hasattr(m, "register")]
    for module in sorted(commands, key=lambda m: getattr(m, "ORDER", 100)):
        module.register(sub)
    return parser


COMMANDS_GROUP = "tspace.commands"


def _version() -> str:
    try:
        return importlib.metadata.version("tspace")
    except importlib.metadata.PackageNotFoundError:
        return "(not installed)"


def plugged_commands() -> list[ModuleType]:
    """Return the command modules other distributions plug in (`tspace.commands` entry points)."""
    found = importlib.metadata.entry_points(group=COMMANDS_GROUP)
    return [entry.load() for entry in sorted(found, key=lambda e: e.name)]


def main(argv: list[str] | None = None) -> int:
    """Run `tspace` and return its exit code; errors become one line on stderr.

    Exit codes: 0 success, 1 failure, 2 usage error (argparse's own, or `UsageError`).
    """
    args = build_parser().parse_args(argv)
    level = [logging.WARNING, logging.INFO, logging.DEBUG][min(args.verbose, 2)]
    logging.basicConfig(level=level, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    try:
        return int(args.func(args) or 0)
    except UsageError as exc:
        print(f"tspace {args.command}: {exc}", file=sys.stderr)
        return 2
    except SpaceError as exc:
        print(f"tspace {args.command}: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0
    except OSError as exc:  # a file or directory the user named (`serve --data`, say)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"tspace {args.command}: {where}{exc.strerror or exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
