"""tspace: a distributed triple space on Eclipse Zenoh."""

from space.ack import Ack, Dropped
from space.changeset import Changeset
from space.client import Transaction, TripleSpace
from space.errors import (
    ChangesetRejected,
    InputError,
    MalformedPayload,
    NotApplied,
    QueryError,
    QueryTimeLimit,
    SpaceError,
    SpaceTimeout,
    SpaceUnavailable,
    TemplateError,
)
from space.lifespan import check_lifespan
from space.subscription import Change, Subscription
from space.template import Template

__all__ = [
    "Ack",
    "Change",
    "Changeset",
    "ChangesetRejected",
    "Dropped",
    "InputError",
    "MalformedPayload",
    "NotApplied",
    "QueryError",
    "QueryTimeLimit",
    "SpaceError",
    "SpaceTimeout",
    "SpaceUnavailable",
    "Subscription",
    "Template",
    "TemplateError",
    "Transaction",
    "TripleSpace",
    "check_lifespan",
]
