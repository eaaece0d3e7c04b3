"""`tspace certs`: the fleet's certificate authority and one certificate per identity."""

from __future__ import annotations

import argparse
from pathlib import Path

ORDER = 80


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `certs` sub-command (`init`, `issue`)."""
    p = sub.add_parser(
        "certs",
        help="make the certificates of a secure fleet (--secure DIR)",
        description=(
            "Make a fleet's CA and a certificate per identity (router, store, operator, "
            "every agent): the certificate's common name is the identity the policy names."
        ),
    )
    actions = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    init = actions.add_parser(
        "init",
        help="a CA (unless DIR has one) and a certificate for every identity of a launch file",
        description=(
            "Make DIR/ca.pem and DIR/ca.key unless they exist, then a key and certificate "
            "for every identity of the launch file that has none yet (existing ones are kept)."
        ),
    )
    init.add_argument("directory", metavar="DIR", type=Path)
    init.add_argument(
        "--fleet", metavar="FILE", required=True, type=Path, help="a launch file (deploy/*.toml)"
    )
    _add_hosts(init)
    init.add_argument(
        "--name", metavar="NAME", action="append", default=[], help="another identity (repeatable)"
    )
    init.set_defaults(func=run_init)
    issue = actions.add_parser(
        "issue",
        help="a new certificate for identities (a new robot, or a rotation)",
        description="Make a new key and certificate for each NAME with DIR's CA, replacing any.",
    )
    issue.add_argument("directory", metavar="DIR", type=Path)
    issue.add_argument("names", metavar="NAME", nargs="+")
    _add_hosts(issue)
    issue.set_defaults(func=run_issue)


def _add_hosts(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--host",
        metavar="ADDR",
        action="append",
        default=[],
        help="an address routers are dialled at, added to router and store certificates "
        "(repeatable; localhost and 127.0.0.1 always are)",
    )


def run_init(args: argparse.Namespace) -> int:
    """Make the CA and the missing certificates; print what was made."""
    from space import _certs
    from space.identity import Identity, check_name

    names = _certs.fleet_identities(args.fleet) + [check_name(n) for n in args.name]
    _certs.init_authority(args.directory)
    made = []
    for name in dict.fromkeys(names):
        if Identity(args.directory, name).cert.exists():
            continue
        _certs.issue(args.directory, name, _certs.hosts_for(name, args.host))
        made.append(name)
    kept = len(set(names)) - len(made)
    print(f"{args.directory}: made {len(made)} certificate(s), kept {kept}: {' '.join(made)}")
    print(f"keep {args.directory / 'ca.key'} off the robots: it signs new identities")
    return 0


def run_issue(args: argparse.Namespace) -> int:
    """Issue (or re-issue) a certificate per name; print them."""
    from space import _certs
    from space.identity import check_name

    for name in args.names:
        check_name(name)
    for name in args.names:
        identity = _certs.issue(args.directory, name, _certs.hosts_for(name, args.host))
        print(f"{identity.cert} {identity.key}")
    return 0
