"""A policy, as the Zenoh access control a secure router enforces.

Zenoh sees key expressions and the peer's certificate CN, nothing else, so
this is the part of the policy that is about keys: servers (routers, stores)
and operators may do anything; every other named identity may read the
space (subscribe, query, fetch the log, watch liveliness), declare its own
liveliness token, and send writes and requests on the keys that carry its own
name, `<root>/<space>/@/write/<CN>` and `<root>/<space>/@/query/<CN>`. So a
store knows who wrote what (the router let only that CN use that key), and
nobody but a server can publish a change notification, declare a queryable or
answer a query (but a reasoner, for its `@/why`). A robot host's own router
(`router.ROBOT`) may pass on what that robot's agents and reasoner may send, so
a robot host taken over still cannot speak for another robot. Revoked
identities are denied everything. The access control applies on the router
that holds it, to the links of its clients: clients must connect to such a
router, never peer with each other.
"""

from __future__ import annotations

from space import keys
from space._policy import Policy, Role

_ALL_MESSAGES = [
    "put",
    "delete",
    "declare_subscriber",
    "query",
    "reply",
    "declare_queryable",
    "liveliness_token",
    "liveliness_query",
    "declare_liveliness_subscriber",
]
_BOTH = ["ingress", "egress"]


def everything(root: str = keys.ROOT) -> list[str]:
    """Return key expressions covering every key of tspace (`@` chunks are not matched by `**`)."""
    return [
        "**",
        f"{root}/*/@/**",
        f"{root}/*/@/changes/@adv/**",  # the changes' advanced publisher: cache, heartbeat
        f"{root}/*/@agents/**",
        f"{root}/*/@reasoners/**",
        f"{root}/@stores/**",
        f"{root}/@repl/**",
        f"{root}/@cluster/**",
        f"{root}/*/@leader/**",
        f"{root}/@leader/**",
    ]


def _reads(root: str) -> list[dict]:
    space = f"{root}/*"
    return [
        _rule(
            "read-subscribe",
            ["declare_subscriber"],
            [
                f"{root}/**",
                f"{space}/@/changes",
                f"{space}/@/changes/*/**",  # parts: a subject, then its predicates
                f"{space}/@/changes/end",
                f"{space}/@/seq",
                f"{root}/@cluster/*",
                f"{space}/@/changes/@adv/**",  # the store's cache's heartbeat
            ],
        ),
        _rule(
            "read-query",
            ["query"],
            [
                f"{space}/t/**",
                f"{space}/i/**",
                f"{space}/@/query",
                f"{space}/@/log",
                f"{space}/@/changes/@adv/**",
                f"{space}/@/why",
            ],
        ),
        _rule(
            "read-liveliness",
            ["liveliness_query", "declare_liveliness_subscriber"],
            [
                f"{root}/**",
                f"{space}/@agents/**",
                f"{space}/@reasoners/**",
                f"{root}/@stores/**",
                f"{root}/@leader/**",
            ],
        ),
        # What the router sends a client: samples, replies, liveliness, only for what it asked.
        {
            "id": "deliver",
            "messages": _ALL_MESSAGES,
            "flows": ["egress"],
            "permission": "allow",
            "key_exprs": everything(root),
        },
    ]


def access_control(policy: Policy, root: str = keys.ROOT) -> dict:
    """Return the `access_control` section of a secure router's Zenoh configuration."""
    rules: list[dict] = [
        {
            "id": "all",
            "messages": _ALL_MESSAGES,
            "flows": _BOTH,
            "permission": "allow",
            "key_exprs": everything(root),
        },
        *_reads(root),
        _rule("reasoner-roster", ["liveliness_token"], [f"{root}/*/@reasoners/*"]),
        # A reasoner explains its conclusions (`tspace why`): its one queryable.
        _rule("reasoner-why", ["declare_queryable", "reply"], [f"{root}/*/@/why"]),
    ]
    subjects: list[dict] = []
    policies: list[dict] = []

    def grant(subject_id: str, names: list[str], rule_ids: list[str]) -> None:
        if names:
            subjects.append({"id": subject_id, "cert_common_names": names})
            policies.append({"rules": rule_ids, "subjects": [subject_id]})

    grant("trusted", policy.named(Role.SERVER, Role.OPERATOR), ["all"])
    members = policy.named(Role.REASONER, Role.ROBOT_AGENT, Role.WRITER)
    reads = [r["id"] for r in _reads(root)]
    crews: dict[str, list[str]] = {}
    for index, name in enumerate(members):
        own = f"own-{index}"
        rules.append(
            _rule(
                own,
                ["put", "query"],
                [
                    f"{root}/*/@/write/{name}",
                    f"{root}/*/@/query/{name}",
                ],
            )
        )
        rules.append(_rule(f"token-{index}", ["liveliness_token"], [f"{root}/*/@agents/{name}"]))
        extra = ["reasoner-roster", "reasoner-why"] if policy.roles[name] is Role.REASONER else []
        crews[name] = [own, f"token-{index}", *extra]
        grant(f"member-{index}", [name], [*reads, *crews[name]])
    # A robot host's router passes on what its robot's own processes may send, nothing else.
    for index, name in enumerate(policy.named(Role.ROBOT_ROUTER)):
        robot = name.removeprefix("router.")
        own = sorted({rule for member in policy.crew_of(robot) for rule in crews[member]})
        grant(f"robot-router-{index}", [name], [*reads, *own])
    if policy.revoked:
        rules.append(
            {
                "id": "revoked",
                "messages": _ALL_MESSAGES,
                "flows": _BOTH,
                "permission": "deny",
                "key_exprs": everything(root),
            }
        )
        grant("revoked", sorted(policy.revoked), ["revoked"])
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def _rule(rule_id: str, messages: list[str], key_exprs: list[str]) -> dict:
    return {
        "id": rule_id,
        "messages": messages,
        "flows": ["ingress"],
        "permission": "allow",
        "key_exprs": key_exprs,
    }
