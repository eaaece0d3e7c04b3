"""Subscribe (with snapshot) and print each change as a JSON line until SIGTERM."""

import json
import signal
import sys
import threading

from space import TripleSpace


def main(endpoint: str, space: str) -> None:
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())

    def show(change) -> None:
        line = {
            "seq": change.seq,
            "added": [[str(x) for x in t] for t in change.added],
            "removed": [[str(x) for x in t] for t in change.removed],
        }
        print(json.dumps(line), flush=True)

    with TripleSpace.open(endpoint, space=space, agent="subscriber") as ts:
        ts.subscribe(None, show, snapshot=True)
        stop.wait()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
