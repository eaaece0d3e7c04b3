"""tspace: a distributed triple space on Eclipse Zenoh.

This list is the library's API: an application (the robot's agents under
`agents/`) imports from here and from `space.reasoning`, nothing deeper.
"""

from space._display import triple_text
from space._heap import freeze_startup, refreeze
from space._paths import default_data_dir
from space._ports import any_free_port
from space._ports import probe as probe_port
from space._request import Pending
from space._session import check_can_listen
from space._subscription import Change, Subscription
from space._turtle import read_turtle
from space.ack import Ack, Dropped
from space.changeset import Changeset
from space.cli.options import add_connect, identity_of
from space.client import Transaction, TripleSpace
from space.cluster_status import ClusterWatch
from space.errors import (
    ChangesetRejected,
    InputError,
    MalformedPayload,
    NoQuorum,
    NoReasoner,
    NotApplied,
    QueryError,
    QueryTimeLimit,
    SpaceError,
    SpaceTimeout,
    SpaceUnavailable,
    TemplateError,
)
from space.explanation import Explanation, Written
from space.functional import Replacement, declares_functional, replace_functional
from space.identity import Identity, load_identity
from space.keys import ROOT as KEY_ROOT
from space.keys import escape as escape_key_chunk
from space.keys import unescape as unescape_key_chunk
from space.lifespan import EXPIRY_AGENT, check_lifespan
from space.mirror import ChangeRecord, SpaceMirror
from space.prefixes import PrefixMap
from space.presence import alive_agents, declare_agent, watch_agents
from space.template import Template
from space.terms import Triple, from_nt, triple_to_nt
from space.why import WhyService
from space.zconfig import DEFAULT_ENDPOINT, SECURE_ENDPOINT, make_config

__all__ = [
    "DEFAULT_ENDPOINT",
    "EXPIRY_AGENT",
    "KEY_ROOT",
    "SECURE_ENDPOINT",
    "Ack",
    "Change",
    "ChangeRecord",
    "Changeset",
    "ChangesetRejected",
    "ClusterWatch",
    "Dropped",
    "Explanation",
    "Identity",
    "InputError",
    "MalformedPayload",
    "NoQuorum",
    "NoReasoner",
    "NotApplied",
    "Pending",
    "PrefixMap",
    "QueryError",
    "QueryTimeLimit",
    "Replacement",
    "SpaceError",
    "SpaceMirror",
    "SpaceTimeout",
    "SpaceUnavailable",
    "Subscription",
    "Template",
    "TemplateError",
    "Transaction",
    "Triple",
    "TripleSpace",
    "WhyService",
    "Written",
    "add_connect",
    "alive_agents",
    "any_free_port",
    "check_can_listen",
    "check_lifespan",
    "declare_agent",
    "declares_functional",
    "default_data_dir",
    "escape_key_chunk",
    "freeze_startup",
    "from_nt",
    "identity_of",
    "load_identity",
    "make_config",
    "probe_port",
    "read_turtle",
    "refreeze",
    "replace_functional",
    "triple_text",
    "triple_to_nt",
    "unescape_key_chunk",
    "watch_agents",
]
