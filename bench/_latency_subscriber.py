"""Child process of space_bench: print the delay of each change (monotonic clock, shared by
processes on Linux) whose object is the writer's send time in nanoseconds."""

import sys
import threading
import time

from space import TripleSpace


def main(endpoint: str, space: str) -> None:
    done = threading.Event()
    delays: list[int] = []

    def on_change(change) -> None:
        now = time.monotonic_ns()
        for t in change.added:
            sent = int(t[2])
            if sent < 0:
                done.set()
                return
            delays.append(now - sent)

    with TripleSpace.open(endpoint, space=space) as ts:
        ts.subscribe("?s <urn:bench:t> ?o", on_change)
        print("ready", flush=True)
        done.wait()
    print(" ".join(str(d) for d in delays), flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
