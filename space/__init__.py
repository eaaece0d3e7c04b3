"""tspace: a distributed triple space on Eclipse Zenoh."""

from space.changeset import Changeset
from space.client import Transaction, TripleSpace
from space.errors import (
    ChangesetRejected,
    InputError,
    MalformedPayload,
    NoReasoner,
    QueryError,
    SpaceError,
    SpaceTimeout,
    SpaceUnavailable,
    TemplateError,
)
from space.explanation import Explanation, Written
from space.subscription import Change, Subscription
from space.template import Template

__all__ = [
    "Change",
    "Changeset",
    "ChangesetRejected",
    "Explanation",
    "InputError",
    "MalformedPayload",
    "NoReasoner",
    "QueryError",
    "SpaceError",
    "SpaceTimeout",
    "SpaceUnavailable",
    "Subscription",
    "Template",
    "TemplateError",
    "Transaction",
    "TripleSpace",
    "Written",
]
