"""Who may write what in a secure space: the policy file, read and checked.

The policy names identities (certificate common names) and gives each a role.
`space._acl` turns it into the Zenoh access control a router enforces (who
may connect, serve, publish changes, and write under which name); a store
hands it to `space.store.guard`, which checks the triples of every write,
what Zenoh cannot see. See deploy/policy.toml for the format.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path

from rdflib import URIRef

from space.errors import InputError
from space.identity import check_name

_PNAME_RE = re.compile(r"^([A-Za-z][A-Za-z0-9_.-]*):(.*)$")
_TOP = {
    "revoked",
    "robots",
    "prefixes",
    "servers",
    "operators",
    "reasoners",
    "robot_agents",
    "robot_routers",
    "writers",
}


class Role(Enum):
    """What an identity is to the space."""

    SERVER = "server"  # routes, keeps the space, publishes its changes, answers its queries
    OPERATOR = "operator"  # may do anything
    REASONER = "reasoner"  # writes asserted and inferred triples about anything
    ROBOT_AGENT = "robot agent"  # writes its robot's things
    ROBOT_ROUTER = "robot router"  # passes on what its robot's agents and reasoner may send
    WRITER = "writer"  # writes some predicates, about anything


@dataclass(frozen=True)
class Policy:
    """A read policy: every identity it names, with its role and what it may write."""

    roles: dict[str, Role]
    robot_of: dict[str, URIRef] = field(default_factory=dict)
    predicates: dict[str, frozenset[URIRef]] = field(default_factory=dict)
    links: tuple[URIRef, ...] = ()
    backlinks: tuple[URIRef, ...] = ()
    revoked: frozenset[str] = frozenset()

    def role(self, identity: str | None) -> Role | None:
        """Return the role of an identity; None if the policy does not name it or revokes it."""
        if identity is None or identity in self.revoked:
            return None
        return self.roles.get(identity)

    def crew_of(self, robot: str) -> list[str]:
        """Return the robot agents and reasoner named `KIND.robot`, revoked ones left out."""
        mine = (Role.ROBOT_AGENT, Role.REASONER)
        return [n for n in self.named(*mine) if n.endswith(f".{robot}")]

    def named(self, *roles: Role) -> list[str]:
        """Return the identities with one of `roles`, revoked ones left out, sorted."""
        return sorted(n for n, r in self.roles.items() if r in roles and n not in self.revoked)


def read_policy(path: str | Path) -> Policy:
    """Read a policy file (TOML).

    Raises:
        InputError: the file cannot be read, is not TOML, or says something this
            reader does not understand (an unknown key, a name that cannot be a
            certificate's CN, a prefix it does not declare); the message names it.
    """
    try:
        data = tomllib.loads(Path(path).read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise InputError(f"{path}: {exc}") from exc
    try:
        return _build(data)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from exc


def _build(data: dict) -> Policy:
    unknown = set(data) - _TOP
    if unknown:
        raise InputError(f"unknown keys {sorted(unknown)}")
    prefixes = _table(data, "prefixes")
    expand = _Expander({k: str(v) for k, v in prefixes.items()})
    roles: dict[str, Role] = {}

    def give(names: Iterable[str], role: Role, where: str) -> None:
        for name in names:
            if name in roles and roles[name] is not role:
                raise InputError(f"{where}: {name!r} already has the role {roles[name].value}")
            roles[check_name(name)] = role

    give(_names(data, "servers"), Role.SERVER, "servers")
    give(_names(data, "operators"), Role.OPERATOR, "operators")
    robots = _strings(data.get("robots", []), "robots")
    reasoners = _table(data, "reasoners")
    give(_strings(reasoners.get("names", []), "reasoners.names"), Role.REASONER, "reasoners")
    if reasoners.get("per_robot", False):
        give([f"reasoner.{r}" for r in robots], Role.REASONER, "reasoners")
    agents = _table(data, "robot_agents")
    kinds = _strings(agents.get("kinds", []), "robot_agents.kinds")
    per_robot_routers = _table(data, "robot_routers").get("per_robot", False)
    namespace = ""
    if kinds or per_robot_routers:  # a robot's IRI is the namespace and its name
        if "namespace" not in agents:
            raise InputError('robot_agents.namespace: the namespace of robots\' IRIs ("ac:")')
        namespace = expand(str(agents["namespace"]), "robot_agents.namespace")
    robot_of: dict[str, URIRef] = {}
    for kind in kinds:
        for robot in robots:
            robot_of[f"{kind}.{robot}"] = URIRef(f"{namespace}{robot}")
    give(robot_of, Role.ROBOT_AGENT, "robot_agents")
    if per_robot_routers:
        routers = {f"router.{r}": URIRef(f"{namespace}{r}") for r in robots}
        give(routers, Role.ROBOT_ROUTER, "robot_routers")
        robot_of.update(routers)
    predicates: dict[str, frozenset[URIRef]] = {}
    for name, entry in _table(data, "writers").items():
        if not isinstance(entry, dict):
            raise InputError(f"writers.{name} must be a table with predicates = [...]")
        where = f"writers.{name}.predicates"
        predicates[name] = frozenset(
            expand(p, where) for p in _strings(entry.get("predicates", []), where)
        )
    give(predicates, Role.WRITER, "writers")
    return Policy(
        roles=roles,
        robot_of=robot_of,
        predicates=predicates,
        links=tuple(
            expand(p, "robot_agents.links")
            for p in _strings(agents.get("links", []), "robot_agents.links")
        ),
        backlinks=tuple(
            expand(p, "robot_agents.backlinks")
            for p in _strings(agents.get("backlinks", []), "robot_agents.backlinks")
        ),
        revoked=frozenset(check_name(n) for n in _strings(data.get("revoked", []), "revoked")),
    )


class _Expander:
    def __init__(self, prefixes: dict[str, str]) -> None:
        self.prefixes = prefixes

    def __call__(self, text: str, where: str) -> URIRef:
        if text.startswith("<") and text.endswith(">"):
            return URIRef(text[1:-1])
        found = _PNAME_RE.match(text)
        if found is None or found.group(1) not in self.prefixes:
            raise InputError(f"{where}: {text!r} is neither <iri> nor a declared prefix:name")
        return URIRef(self.prefixes[found.group(1)] + found.group(2))


def _table(data: dict, key: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise InputError(f"{key} must be a table")
    return value


def _names(data: dict, key: str) -> list[str]:
    return _strings(_table(data, key).get("names", []), f"{key}.names")


def _strings(value: object, where: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise InputError(f"{where} must be a list of strings, got {value!r}")
    return list(value)
