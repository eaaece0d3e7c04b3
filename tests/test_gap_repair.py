"""Changes a router drops while every link stays up still arrive, in order, once each.

The subscriber's router passes only a few whole changesets a second (Zenoh's own
`downsampling`: the loss of a congested route, with no reconnection nor store token
coming back to say so). The store's advanced publisher's cache fills the gap the next
change that gets through shows, or the last change's heartbeat; what the cache no
longer holds comes from the store's log.
"""

import json

import pytest
import zenoh
from rdflib import Literal, Namespace

from conftest import AC_NS, free_port, wait_for
from space import TripleSpace, keys, make_config
from space.store.publish import CACHE

AC = Namespace(AC_NS)


@pytest.mark.parametrize("count", [40, 3 * CACHE], ids=["within-cache", "past-cache"])
def test_changes_a_router_drops_come_back_in_order_once_each(server, space_name, count):
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    conf = make_config(mode="router", listen=[endpoint], connect=[server.endpoint])
    key = keys.service_key(space_name, "changes", keys.ROOT)
    drop = {"messages": ["put"], "flows": ["egress"], "rules": [{"key_expr": key, "freq": 5.0}]}
    conf.insert_json5("downsampling", json.dumps([drop]))
    with (
        zenoh.open(conf),
        TripleSpace.open(endpoint, space=space_name) as sub_side,
        TripleSpace.open(server.endpoint, space=space_name) as writer,
    ):
        seen = []
        sub_side.subscribe(None, seen.append)
        for i in range(count):
            writer.write_nowait([(AC[f"s{i}"], AC.n, Literal(i))])
        wait_for(lambda: len(seen) >= count, 20, "every change, the last ones on a heartbeat")
        assert [int(c.added[0][2]) for c in seen] == list(range(count))
        first = seen[0].seq
        assert [c.seq for c in seen] == list(range(first, first + count))
