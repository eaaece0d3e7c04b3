"""`tspace up`: run a whole deployment (store, reasoner, agents, HMI) from a launch file."""

from __future__ import annotations

import argparse
from pathlib import Path

from space import DEFAULT_ENDPOINT, SECURE_ENDPOINT

ORDER = 10
DEFAULT_LAUNCH = Path("deploy/hospital.toml")
POLICY = Path("deploy/policy.toml")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `up` sub-command."""
    p = sub.add_parser(
        "up",
        help="run the store and every agent of a launch file, with a live view",
        description=(
            "Start `tspace serve` and every agent of the launch file as separate processes, "
            "restart those that crash, show the robots live, stop everything on Ctrl-C. "
            "A space that holds something is resumed where it was; `tspace up --fresh` is the "
            "reset: it empties the space (in one changeset, before any agent starts) and "
            "loads the launch file's state."
        ),
    )
    p.add_argument(
        "launch",
        nargs="?",
        type=Path,
        help=f"the launch file (default {DEFAULT_LAUNCH}, here or in the project's folder)",
    )
    p.add_argument(
        "--listen",
        metavar="ENDPOINT",
        action="append",
        help=f"endpoint the store's router listens on (repeatable; default {DEFAULT_ENDPOINT})",
    )
    p.add_argument(
        "--data",
        metavar="DIR",
        type=Path,
        help="where the store persists (default $XDG_DATA_HOME/tspace, else ~/.local/share/tspace)",
    )
    p.add_argument(
        "--hmi-port", type=int, metavar="PORT", help="HTTP port of the HMI (overrides the file)"
    )
    p.add_argument(
        "--hmi-listen",
        metavar="HOST",
        help="address the HMI serves on (default 127.0.0.1: this machine only; 0.0.0.0: every "
        "interface, for a tablet on the ward's network)",
    )
    p.add_argument(
        "--fresh",
        action="store_true",
        help="start over: empty the space and load the launch file's state (default: resume "
        "where it was; a --scenario always starts afresh)",
    )
    p.add_argument(
        "--raw-firings",
        action="store_true",
        help="show rule firings as their triples and cause, not as sentences",
    )
    p.add_argument(
        "--scenario", metavar="NAME", help="play a scenario (battery: the paper's example)"
    )
    p.add_argument(
        "--once",
        action="store_true",
        help="with --scenario: exit 0 when it completes, non-zero naming the step that did not",
    )
    p.add_argument(
        "--step-timeout",
        type=float,
        default=90.0,
        metavar="SECONDS",
        help="how long each scenario step may take (default 90)",
    )
    p.add_argument(
        "--secure",
        metavar="DIR",
        type=Path,
        help="mutual TLS on every link, each process with its own certificate from DIR "
        "(tspace certs init); the router enforces --policy",
    )
    p.add_argument(
        "--policy",
        metavar="FILE",
        type=Path,
        help=f"with --secure: who may do what (default {POLICY}, here or in the project's folder)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the deployment until Ctrl-C, SIGTERM, or the end of a `--once` scenario."""
    from agents.resources import shipped
    from agents.runtime.deployment import Deployment, Options
    from agents.runtime.launch import read_launch
    from agents.runtime.liveview import LiveView
    from agents.runtime.scenario import SCENARIOS
    from space import InputError, default_data_dir

    if args.policy and not args.secure:
        raise InputError("--policy needs --secure DIR")
    if args.once and not args.scenario:
        raise InputError("--once needs --scenario")
    if args.scenario and args.scenario not in SCENARIOS:
        raise InputError(f"unknown scenario {args.scenario!r}; known: {', '.join(SCENARIOS)}")
    options = Options(
        launch=read_launch(args.launch or shipped(DEFAULT_LAUNCH)),
        listen=args.listen or [SECURE_ENDPOINT if args.secure else DEFAULT_ENDPOINT],
        data=args.data or default_data_dir(),
        hmi_port=args.hmi_port,
        scenario=SCENARIOS[args.scenario] if args.scenario else None,
        once=args.once,
        step_timeout=args.step_timeout,
        fresh=args.fresh,
        hmi_listen=args.hmi_listen,
        secure=args.secure,
        policy=args.policy or (shipped(POLICY) if args.secure else None),
    )
    return Deployment(options, LiveView.for_terminal(raw=args.raw_firings)).run()
