"""Write COUNT changesets of one triple each (`ac:counter ac:n i`), then exit."""

import sys

from rdflib import Literal, Namespace

from space import TripleSpace

AC = Namespace("https://w3id.org/tspace/selfconfig#")


def main(endpoint: str, space: str, count: int) -> None:
    with TripleSpace.open(endpoint, space=space, agent="writer") as ts:
        for i in range(count):
            ts.write([(AC.counter, AC.n, Literal(i))])
            print(i, flush=True)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]))
