"""Child processes of space_bench's latency measure, run from the tree under test.

`subscribe ENDPOINT SPACE`: print the delay of each change (monotonic clock, shared by
processes on Linux) whose object is the writer's send time in nanoseconds.
`write ENDPOINT SPACE COUNT [nowait]`: write COUNT one-triple changesets so, then the end mark.
"""

import sys
import threading
import time

from rdflib import Literal, URIRef

from space import TripleSpace

T = URIRef("urn:bench:t")


def subscribe(endpoint: str, space: str) -> None:
    done = threading.Event()
    delays: list[int] = []

    def on_change(change) -> None:
        now = time.monotonic_ns()
        for t in change.added:
            sent = int(t[2])
            if sent < 0:
                done.set()
                return
            if sent:  # 0: the writer's warm-up write, not a measured one
                delays.append(now - sent)

    with TripleSpace.open(endpoint, space=space) as ts:
        ts.subscribe("?s <urn:bench:t> ?o", on_change)
        print("ready", flush=True)
        done.wait()
    print(" ".join(str(d) for d in delays), flush=True)


def write(endpoint: str, space: str, count: int, nowait: bool) -> None:
    with TripleSpace.open(endpoint, space=space, agent="bench") as ts:
        ts.write([(URIRef("urn:bench:start"), T, Literal(0))])  # the session's paths warmed up
        for i in range(count):
            triple = (URIRef(f"urn:bench:s{i % 10}"), T, Literal(time.monotonic_ns()))
            if nowait:
                ts.write_nowait([triple])
                time.sleep(0.002)  # one changeset at a time, as a sensor would
            else:
                ts.write([triple])
        ts.write([(URIRef("urn:bench:end"), T, Literal(-1))])


if __name__ == "__main__":
    if sys.argv[1] == "subscribe":
        subscribe(sys.argv[2], sys.argv[3])
    else:
        write(sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5:] == ["nowait"])
