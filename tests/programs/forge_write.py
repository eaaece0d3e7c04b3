"""Send a changeset on a write key as IDENTITY, straight over Zenoh; print the replies.

    forge_write.py ENDPOINT CERTS IDENTITY KEY TURTLE

Prints `replies N` (N: how many answers the GET got within 3 s; 0 when the key
is not the identity's to use and a router dropped it) and each reply's text.
"""

import sys

import zenoh
from rdflib import Graph

from space import load_identity
from space.changeset import Changeset
from space.zconfig import make_config


def main(endpoint: str, certs: str, identity: str, key: str, turtle: str) -> None:
    conf = make_config(connect=[endpoint], identity=load_identity(certs, identity))
    payload = Changeset(added=list(Graph().parse(data=turtle, format="turtle"))).encode()
    session = zenoh.open(conf)
    try:
        replies = list(session.get(key, payload=payload, timeout=3.0))
        print(f"replies {len(replies)}", flush=True)
        for reply in replies:
            sample = reply.ok if reply.ok is not None else reply.err
            print(sample.payload.to_bytes().decode(errors="replace"), flush=True)
    finally:
        session.close()


if __name__ == "__main__":
    main(*sys.argv[1:6])
