"""Errors of the triple space, named for what went wrong."""

from __future__ import annotations


class SpaceError(Exception):
    """Base class of every error tspace raises on purpose."""


class SpaceUnavailable(SpaceError):
    """No store answered within the timeout (router down or no `tspace serve`)."""


class SpaceTimeout(SpaceError):
    """A store was reachable but did not answer in time (a write may still be applied)."""


class ConfigError(SpaceError, ValueError):
    """A Zenoh endpoint or configuration file given by the user is malformed."""


class NoReasoner(SpaceUnavailable):
    """No reasoner answered a `why` (none runs on the space, or it did not answer in time)."""


class ListenFailed(SpaceError):
    """A router could not listen on an endpoint (address in use, not an address of this host)."""


class ChangesetRejected(SpaceError):
    """The store refused a changeset (malformed, or it could not persist it)."""


class MalformedPayload(SpaceError):
    """A payload or key from the network could not be decoded."""


class TemplateError(SpaceError, ValueError):
    """A triple template could not be parsed."""


class QueryError(SpaceError):
    """A SPARQL query was rejected by the store (syntax or evaluation error)."""


class QueryTimeLimit(QueryError):
    """A read ran past its time limit at the store (the message names it); the store lives on."""


class NotApplied(SpaceError):
    """A strict write was acknowledged with triples not applied (`ack.dropped` says which and why).

    The rest of the changeset is applied and durable: this is not a rejection.
    """

    def __init__(self, ack: object, message: str) -> None:
        super().__init__(message)
        self.ack = ack


class InputError(SpaceError, ValueError):
    """A document or name given by the user (Turtle file, template, space name) is malformed."""


class NoQuorum(SpaceUnavailable):
    """Too few etcd members are reachable to commit anything: this side of a cut is a minority."""

    def __init__(self, reachable: int, members: int, detail: str = "") -> None:
        self.reachable, self.members = reachable, members
        more = f" ({detail})" if detail else ""
        super().__init__(f"no quorum: {reachable} of {members} members reachable{more}")


class ClusterError(SpaceError):
    """etcd refused a request for a reason retrying cannot fix (quota full, bad request)."""


class WriteConflict(SpaceError):
    """A compare-and-swap failed: what the decision read changed before it committed."""

    def __init__(self, keys: list[bytes]) -> None:
        self.keys = keys
        super().__init__(f"{len(keys)} key(s) changed since they were read")


class UsageError(SpaceError):
    """A command line asks for something its options cannot mean (exit 2, as argparse's)."""


def clause(reason: str) -> str:
    """Return an OS or Zenoh reason to follow a colon: "Address in use" -> "address in use"."""
    return reason[:1].lower() + reason[1:]
