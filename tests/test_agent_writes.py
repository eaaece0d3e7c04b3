"""An agent's loop never waits for the store: writes are sent, settled later, failures undone."""

from __future__ import annotations

import time

import pytest
from rdflib import Literal, Namespace

from agents.base import Agent, build_parser
from conftest import Server, wait_for
from space import TripleSpace

EX = Namespace("http://example.org/")


@pytest.fixture
def agent(tmp_path):
    srv = Server(tmp_path / "data")
    srv.start()
    args = build_parser(Agent).parse_args(
        ["--connect", srv.endpoint, "--space", "writes", "--timeout", "1", "--wait", "10"]
    )
    agent = Agent(args)
    try:
        agent.setup()
        yield agent, srv
    finally:
        agent.shutdown()
        srv.stop()


def test_a_write_lands_without_the_loop_waiting_for_it(agent):
    agent, srv = agent
    sent = agent.set_values({(EX.robot, EX.speed): Literal("low")})
    assert sent is not None
    with TripleSpace.open(srv.endpoint, space="writes") as ts:
        wait_for(lambda: len(ts.query((EX.robot, EX.speed, Literal("low")))) == 1)
    assert agent.writes.failed() == []


def test_with_the_store_gone_a_write_returns_at_once_and_its_failure_is_undone(agent):
    agent, srv = agent
    agent.set_values({(EX.robot, EX.speed): Literal("low")})
    wait_for(lambda: agent.writes.in_flight == 0)
    srv.stop()
    started = time.monotonic()
    agent.set_values({(EX.robot, EX.speed): Literal("high")})
    assert time.monotonic() - started < 0.5  # the store's timeout is 1 s: it did not wait
    assert agent.view.objects(EX.robot, EX.speed) == [Literal("high")]

    def undone() -> bool:
        agent._surface_failed_writes()
        return agent.view.objects(EX.robot, EX.speed) == [Literal("low")]

    wait_for(undone, 10, "the failed write undone in the view")
