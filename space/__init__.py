"""tspace: a distributed triple space on Eclipse Zenoh."""

from space.changeset import Changeset
from space.client import Transaction, TripleSpace
from space.errors import (
    ChangesetRejected,
    InputError,
    MalformedPayload,
    QueryError,
    SpaceError,
    SpaceTimeout,
    SpaceUnavailable,
    TemplateError,
)
from space.identity import Identity, load_identity
from space.subscription import Change, Subscription
from space.template import Template

__all__ = [
    "Change",
    "Changeset",
    "ChangesetRejected",
    "Identity",
    "InputError",
    "MalformedPayload",
    "QueryError",
    "SpaceError",
    "SpaceTimeout",
    "SpaceUnavailable",
    "Subscription",
    "Template",
    "TemplateError",
    "Transaction",
    "TripleSpace",
    "load_identity",
]
