"""Write COUNT changesets of one triple each (`ac:counter ac:n i`), INTERVAL s apart, then exit."""

import sys
import time

from rdflib import Literal, Namespace

from space import TripleSpace

AC = Namespace("https://w3id.org/tspace/selfconfig#")


def main(endpoint: str, space: str, count: int, interval: float) -> None:
    with TripleSpace.open(endpoint, space=space, agent="writer") as ts:
        for i in range(count):
            ts.write([(AC.counter, AC.n, Literal(i))])
            print(i, flush=True)
            time.sleep(interval)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4]))
