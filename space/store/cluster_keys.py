"""The etcd keyspace of a clustered space (docs/cluster.md describes it for operators).

Everything lives under one root (`tspace/` by default), so several
deployments can share an etcd cluster and one range covers each kind:

    ROOT log/SPACE            the changesets of SPACE committed at this revision (a list)
    ROOT state/SPACE/G/ID     one triple of graph G (t asserted, i inferred), value its text
    ROOT fn/SPACE/ID          the value and HLC stamp of one (subject, functional property)
    ROOT prefix/SPACE/NAME    a prefix binding of SPACE
    ROOT count/SPACE/J        put by every transaction whose number of changesets of SPACE
                              has bit J set: the sum of version x 2**J is the space's seq
    ROOT req/SPACE/ID         a request id seen in the last minute (leased, 60 s)
    ROOT batch/NODE-ID-N      marks a committed group-commit transaction (leased, 60 s);
                              ID is new in every process, so a marker never repeats
    ROOT replicas/NODE        the revision a live replica has applied (leased)

`state/` and `fn/` are what compare-and-swap decides on, and with `prefix/`
and `count/` what a replica re-lists when its revision was compacted away;
`log/` is what replicas apply, in etcd's revision order.
"""

from __future__ import annotations

import hashlib

ROOT = b"tspace/"


def prefix_end(prefix: bytes) -> bytes:
    """Return the end of the etcd range that holds exactly the keys starting with `prefix`."""
    return prefix[:-1] + bytes([prefix[-1] + 1])


def digest(*texts: str) -> str:
    """Return a short, stable id for an N-Triples term tuple (a key chunk without `/`)."""
    joined = "\x00".join(texts).encode()
    return hashlib.blake2b(joined, digest_size=16).hexdigest()


def log_key(root: bytes, space: str) -> bytes:
    """Return the key whose every revision holds what SPACE committed in it."""
    return root + b"log/" + space.encode()


def log_space(root: bytes, key: bytes) -> str:
    """Return the space a log key belongs to."""
    return key[len(root) + len(b"log/") :].decode()


def state_prefix(root: bytes, space: str = "") -> bytes:
    """Return the prefix of every triple key of SPACE (or of every space, given none)."""
    return root + b"state/" + (space.encode() + b"/" if space else b"")


def triple_key(root: bytes, space: str, graph: str, s: str, p: str, o: str) -> bytes:
    """Return the key of one triple (N-Triples texts) in graph `t` or `i` of SPACE."""
    return state_prefix(root, space) + f"{graph}/{digest(s, p, o)}".encode()


def functional_key(root: bytes, space: str, s: str, p: str) -> bytes:
    """Return the key that guards the value of functional property `p` of subject `s`."""
    return root + b"fn/" + space.encode() + b"/" + digest(s, p).encode()


def batch_key(root: bytes, node: str, n: int) -> bytes:
    """Return the marker key of group-commit transaction `n` of a node (its name and id)."""
    return root + f"batch/{node}-{n}".encode()


def replica_key(root: bytes, node: str) -> bytes:
    """Return the key where replica `node` says which revision it has applied."""
    return root + b"replicas/" + node.encode()


def count_keys(root: bytes, space: str, n: int) -> list[bytes]:
    """Return the counter keys a transaction with `n` changesets of SPACE puts (one per bit)."""
    return [
        root + b"count/" + space.encode() + b"/%d" % j for j in range(n.bit_length()) if n >> j & 1
    ]


def count_weight(key: bytes) -> int:
    """Return how many changesets one put of a counter key stands for (2**J)."""
    return 1 << int(key.rsplit(b"/", 1)[1])


def prefix_key(root: bytes, space: str, name: str) -> bytes:
    """Return the key of prefix `name` of SPACE."""
    return root + b"prefix/" + space.encode() + b"/" + name.encode()


def request_key(root: bytes, space: str, request: str) -> bytes:
    """Return the key that says request `request` of SPACE was committed lately."""
    return root + b"req/" + space.encode() + b"/" + digest(request).encode()
