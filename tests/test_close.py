"""Closing releases everything, even when one step of it fails."""

import pytest
import zenoh

from space import TripleSpace


def test_a_failing_undeclare_still_closes_the_session(server, space_name):
    ts = TripleSpace.open(server.endpoint, space=space_name)
    first = ts.subscribe(None, lambda change: None)
    ts.subscribe(None, lambda change: None)
    first._subscribers[0].undeclare()  # provoke the failure: undeclared behind the handle's back
    with pytest.raises(zenoh.ZError):
        ts.close()
    assert ts.session.is_closed()
