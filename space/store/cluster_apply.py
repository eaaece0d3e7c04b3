"""Revisions etcd committed, installed into a replica's spaces; ours answered once installed.

Every replica installs every changeset of the log, in log order, whoever wrote
it; only the changesets this replica decided (its flights, found by payload,
which names the writer that decided it) are acknowledged and published here,
the others only noted for the publisher.
Apart from `ClusterWriter` because installing is the same whoever decided, and
a malformed revision must be skipped, logged, without stopping the replica.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from space import keys
from space.changeset import pack
from space.errors import MalformedPayload, SpaceError
from space.store.cluster_expiry import ClusterExpiry
from space.store.cluster_flights import Flight
from space.store.cluster_state import ClusterSpace
from space.store.etcd_applier import Batch
from space.store.publish import Publisher
from space.store.state import Net
from space.store.writer import answer

log = logging.getLogger("tspace.store")

Installed = list[tuple[ClusterSpace, Net]]
Ours = list[tuple[Flight, Net]]


def install(
    applied: list[tuple[int, list[Batch]]],
    space: Callable[[str], ClusterSpace],
    by_payload: dict[bytes, Flight],
    expiry: ClusterExpiry,
) -> tuple[Installed, Ours]:
    """Install each revision's changesets into their spaces, in log order.

    Returns:
        Every changeset installed with its space, and those among them that are
        this replica's flights.
    """
    nets: Installed = []
    ours: Ours = []
    for revision, batches in applied:
        for batch in batches:
            try:
                state = space(keys.check_space(batch.space))
            except (SpaceError, ValueError) as exc:
                log.error("revision %d: skipped a space with a bad name: %s", revision, exc)
                continue
            for i, payload in enumerate(batch.payloads):
                try:
                    net = state.install_at(payload, batch.first_seq + i)
                except (MalformedPayload, ValueError) as exc:
                    log.error(
                        "revision %d of %s: skipped a malformed changeset: %s",
                        revision,
                        batch.space,
                        exc,
                    )
                    continue
                nets.append((state, net))
                flight = by_payload.get(payload)
                expiry.applied(state.name, payload, net, ours=flight is not None)
                if flight is not None:
                    ours.append((flight, net))
    return nets, ours


def acknowledge(nets: Installed, ours: Ours, publisher: Publisher) -> None:
    """Answer our flights' writers (and those who asked again), then publish in log order."""
    for flight, net in ours:
        ack = pack(flight.reply(net))
        if flight.req.query is not None:
            flight.req.query.reply(flight.req.key, ack)
            flight.req.query.drop()
        for req in flight.followers:
            answer(req, {**flight.reply(net), "again": True})
    mine = {id(n) for _f, n in ours}
    for state, net in nets:  # in log order: each part names the changeset before it
        if id(net) in mine:
            publisher.publish([(state, net)])
        else:
            publisher.note(state, net)
