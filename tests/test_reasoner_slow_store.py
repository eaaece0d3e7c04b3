"""A store slower than the reasoner's timeout still gets one answer per change, each naming it."""

from __future__ import annotations

import os
import signal
import time

from rdflib import Literal, Namespace

from conftest import wait_for
from space import Change, TripleSpace

EX = Namespace("http://example.org/")
WRITES = 2000  # a burst the reasoner is still answering when the store stalls
STALL = 1.0  # seconds the store is stopped (SIGSTOP): five times the reasoner's --timeout


def test_answers_acknowledged_after_the_timeout_are_not_replaced_by_a_resync(
    ts: TripleSpace, server, launch, tmp_path
):
    rules = tmp_path / "level.rules"
    rules.write_text(
        "@prefix ex: <http://example.org/>.\n[levelled: (?s ex:level ?l) -> (?s ex:kind ex:L)]\n"
    )
    agent = launch.start("reasoner", "--rules", str(rules), "--timeout", "0.2")
    wait_for(lambda: "connected to space" in agent.logs(), 30, "the reasoner", agent.logs)
    answered: set[str] = set()

    def on_change(change: Change) -> None:
        if change.agent == "reasoner" and change.cause:
            answered.add(change.cause)

    sub = ts.subscribe(None, on_change)
    try:
        markers = [
            ts.send_nowait(ts.changeset([(EX[f"s{i}"], EX.level, Literal("low"))]))
            for i in range(WRITES)
        ]
        # The store stalls (a disk or a machine that busy) while answers are in flight: their
        # acknowledgements come later than --timeout.
        wait_for(lambda: len(answered) >= 20, 60, "the reasoner answering", agent.logs)
        os.kill(server.proc.pid, signal.SIGSTOP)
        try:
            time.sleep(STALL)  # the stall is the point
        finally:
            os.kill(server.proc.pid, signal.SIGCONT)
        wait_for(
            lambda: answered >= set(markers),
            120,
            "an answer naming each change the rules answer",
            lambda: (
                f"{len(set(markers) - answered)} of {len(markers)} unanswered\n"
                + agent.logs()[-3000:]
            ),
        )
    finally:
        ts.unsubscribe(sub)
    assert len(ts.query((None, EX.kind, EX.L))) == WRITES
    # The answers were taken, later: not refused, no engine rebuilt (which skipped changes).
    assert "not taken" not in agent.logs()
    assert "resynchronised" not in agent.logs()
    assert "not acknowledged yet: sent again" in agent.logs()  # the stall was seen
