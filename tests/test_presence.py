"""Presence: agents are seen alive while their liveliness token lives, and gone after."""

import zenoh

from conftest import wait_for
from space.presence import alive_agents, declare_agent, watch_agents
from space.zconfig import make_config


def test_agents_come_and_go(ts, space_name):
    events: list[tuple[str, bool]] = []
    watcher = watch_agents(ts.session, space_name, lambda n, alive: events.append((n, alive)))
    try:
        token = declare_agent(ts.session, space_name, "hw_monitor.robot1")
        wait_for(lambda: ("hw_monitor.robot1", True) in events, what="the agent's arrival")
        assert alive_agents(ts.session, space_name) == ["hw_monitor.robot1"]
        token.undeclare()
        wait_for(lambda: ("hw_monitor.robot1", False) in events, what="the agent's departure")
        assert alive_agents(ts.session, space_name) == []
    finally:
        watcher.undeclare()


def test_agent_of_another_space_is_not_seen(ts, space_name):
    token = declare_agent(ts.session, space_name + "other", "reasoner")
    try:
        assert alive_agents(ts.session, space_name) == []
    finally:
        token.undeclare()


def test_a_fleet_of_more_agents_than_a_zenoh_channel_holds_is_listed_whole(ts, server, space_name):
    """Zenoh's default handler holds 256 replies; a fleet's agents may be many more."""
    names = sorted(f"behavior.robot{i}" for i in range(600))
    with zenoh.open(make_config(connect=[server.endpoint])) as fleet:
        tokens = [declare_agent(fleet, space_name, n) for n in names]
        try:
            wait_for(lambda: len(alive_agents(ts.session, space_name)) == 600, what="every agent")
            assert alive_agents(ts.session, space_name) == names
        finally:
            for token in tokens:
                token.undeclare()
