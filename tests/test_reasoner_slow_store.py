"""A store slower than the reasoner's timeout still gets one answer per change, each naming it."""

from __future__ import annotations

from rdflib import Literal, Namespace

from conftest import wait_for
from space import Change, TripleSpace

EX = Namespace("http://example.org/")
WRITES = 2000  # a burst the store takes seconds to commit: far longer than --timeout


def test_answers_acknowledged_after_the_timeout_are_not_replaced_by_a_resync(
    ts: TripleSpace, launch, tmp_path
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
    assert "not acknowledged yet: sent again" in agent.logs()  # the store was that slow
