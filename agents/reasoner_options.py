"""The reasoner's own command-line options: its knowledge, its records, one per robot or not."""

from __future__ import annotations

import argparse
from pathlib import Path


def add_reasoner_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the reasoner's options to an agent's parser (`agents.process.build_parser`)."""
    parser.add_argument(
        "--rules",
        action="append",
        type=Path,
        metavar="FILE",
        help="Jena rules file (repeatable; default rules/selfconfig.rules)",
    )
    parser.add_argument(
        "--ontology",
        action="append",
        type=Path,
        metavar="FILE",
        help="ontology file (repeatable; default ontology/selfconfig.ttl)",
    )
    parser.add_argument(
        "--robot-file",
        type=Path,
        metavar="FILE",
        help="a robot description written into the space if its robot is not there",
    )
    parser.add_argument(
        "--keep-firings",
        type=int,
        default=100,
        metavar="N",
        help="firing records kept in the space (default 100)",
    )
    parser.add_argument(
        "--per-robot",
        action="store_true",
        help="one reasoner per robot: answer for --robot (see agents.ownership)",
    )
