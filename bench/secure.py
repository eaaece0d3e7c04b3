"""What mutual TLS and access control cost: end to end, plain vs secure, in one run.

The end-to-end bench's robot (bench/end_to_end.py: `tspace serve`, reasoner,
hw_monitor, nav_monitor, behaviour, each its own process on loopback; the
project's rules), timed from "battery very low" written by the hw_monitor to
the last agent having acted on it. Plain (TCP, no policy) and secure (`tspace
certs init` certificates, mTLS on every link, the router enforcing
deploy/policy.toml and the store its write guard) alternate, round after
round, so both see the same machine load.

Run: python bench/secure.py [--rounds 3] [--runs 40]
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from _harness import median, percentile
from _output import bench_parser, parse, print_table
from end_to_end import RuleSet, measure

from space import _certs

ROBOT_AGENTS = ["reasoner", "hw_monitor.robot1", "nav_monitor.robot1", "behavior.robot1"]


def make_certs(directory: Path) -> Path:
    """Make a CA and the certificates of the bench's processes in `directory`."""
    _certs.init_authority(directory)
    for name in [*_certs.SERVERS, _certs.OPERATOR, *ROBOT_AGENTS]:
        _certs.issue(directory, name, _certs.hosts_for(name))
    return directory


def main(rounds: int, runs: int) -> None:
    last: dict[str, list[float]] = {"plain": [], "secure": []}
    per_round: dict[str, list[float]] = {"plain": [], "secure": []}
    with tempfile.TemporaryDirectory(prefix="tspace-secure-") as tmp:
        certs = make_certs(Path(tmp) / "certs")
        for index in range(rounds):
            for mode in ("plain", "secure"):
                logs = Path(tmp) / f"{mode}-{index}"
                logs.mkdir()
                results, _load = measure(runs, RuleSet(), logs, certs if mode == "secure" else None)
                values = [r["last"] for r in results]
                last[mode] += values
                per_round[mode].append(median(values))
                print(f"round {index + 1} {mode}: last p50 {median(values):.2f} ms", flush=True)
    rows = [
        [
            mode,
            len(values),
            ", ".join(f"{v:.2f}" for v in per_round[mode]),
            median(per_round[mode]),
            median(values),
            percentile(values, 99),
        ]
        for mode, values in last.items()
    ]
    print_table(
        f'"battery very low" -> last agent acted (ms; {rounds} rounds x {runs} runs, '
        "plain and secure alternating)",
        [
            "mode",
            "runs",
            "p50 per round (ms)",
            "median of rounds (ms)",
            "p50 all (ms)",
            "p99 all (ms)",
        ],
        rows,
    )


if __name__ == "__main__":
    parser = bench_parser(__doc__)
    parser.add_argument("--rounds", type=int, default=3, help="plain/secure pairs (default 3)")
    parser.add_argument("--runs", type=int, default=40, help="very low batteries per round")
    options = parse(parser)
    main(options.rounds, options.runs)
