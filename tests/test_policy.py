"""The policy file: read into roles, turned into Zenoh access control; bad files named clearly."""

from __future__ import annotations

from pathlib import Path

import pytest
from rdflib import URIRef

from conftest import AC_NS, REPO
from space import InputError
from space._acl import access_control
from space._policy import Role, read_policy

SHIPPED = REPO / "deploy" / "policy.toml"


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "policy.toml"
    path.write_text(text)
    return path


def test_the_shipped_policy_gives_every_fleet_identity_its_role():
    policy = read_policy(SHIPPED)
    assert policy.role("store") is Role.SERVER and policy.role("router") is Role.SERVER
    assert policy.role("operator") is Role.OPERATOR
    assert policy.role("reasoner") is Role.REASONER
    assert policy.role("reasoner.robot2") is Role.REASONER
    assert policy.role("hw_monitor.robot2") is Role.ROBOT_AGENT
    assert policy.robot_of["hw_monitor.robot2"] == URIRef(AC_NS + "robot2")
    assert policy.role("router.guide1") is Role.ROBOT_ROUTER
    assert policy.role("hmi") is Role.WRITER
    assert URIRef(AC_NS + "requested_task") in policy.predicates["hmi"]
    assert policy.role("visitor") is None


def test_access_control_gives_each_identity_its_own_write_key_and_denies_the_revoked(tmp_path):
    text = SHIPPED.read_text().replace("revoked = []", 'revoked = ["behavior.robot1"]', 1)
    acl = access_control(read_policy(write(tmp_path, text)))
    assert acl["enabled"] and acl["default_permission"] == "deny"
    rules = {r["id"]: r for r in acl["rules"]}
    subjects = {s["id"]: s["cert_common_names"] for s in acl["subjects"]}

    def rules_of(name: str) -> list[dict]:
        ids = {s for s, names in subjects.items() if name in names}
        return [rules[r] for p in acl["policies"] if set(p["subjects"]) & ids for r in p["rules"]]

    writes = {
        key
        for r in rules_of("hw_monitor.robot2")
        if "put" in r["messages"] and "ingress" in r["flows"]
        for key in r["key_exprs"]
    }
    assert writes == {
        "tspace/*/@/write/hw_monitor.robot2",
        "tspace/*/@/query/hw_monitor.robot2",
    }
    ingress = [r for r in rules_of("hw_monitor.robot2") if "ingress" in r["flows"]]
    assert not any({"reply", "declare_queryable"} & set(r["messages"]) for r in ingress)
    router_writes = {
        key
        for r in rules_of("router.robot2")
        if "put" in r["messages"]
        for key in r["key_exprs"]
        if "@/write/" in key
    }
    assert router_writes == {
        f"tspace/*/@/write/{n}"
        for n in ("hw_monitor.robot2", "nav_monitor.robot2", "behavior.robot2", "reasoner.robot2")
    }
    revoked = rules_of("behavior.robot1")
    assert revoked and all(r["permission"] == "deny" for r in revoked)
    assert "behavior.robot1" not in {n for names in subjects.values() for n in names} - set(
        subjects["revoked"]
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("servers = [\n", "policy.toml: "),  # TOML syntax: tomllib names line and column
        ("colour = 1\n", "unknown keys ['colour']"),
        ('[writers.hmi]\npredicates = ["foo:bar"]\n', "writers.hmi.predicates: 'foo:bar'"),
        ('[servers]\nnames = ["a router"]\n', "identity 'a router'"),
        ('[servers]\nnames = ["x"]\n[operators]\nnames = ["x"]\n', "'x' already has the role"),
        ('robots = "robot1"\n', "robots must be a list of strings"),
        ('[robot_agents]\nkinds = ["hw_monitor"]\n', "robot_agents.namespace: the namespace"),
    ],
)
def test_a_bad_policy_is_one_clear_error_naming_the_file(tmp_path, text, message):
    with pytest.raises(InputError, match=r"policy\.toml") as raised:
        read_policy(write(tmp_path, text))
    assert message in str(raised.value)
