"""Presence: which agents are alive, through Zenoh liveliness tokens."""

from __future__ import annotations

from collections.abc import Callable

import zenoh

from space import keys
from space._replies import every_reply


def agent_key(space: str, name: str, root: str = keys.ROOT) -> str:
    """Return the liveliness key of an agent (its name escaped like a key chunk)."""
    return f"{root}/{space}/@agents/{keys.escape(name)}"


def agents_key(space: str, root: str = keys.ROOT) -> str:
    """Return the key expression that matches every agent of a space."""
    return f"{root}/{space}/@agents/*"


def declare_agent(session: zenoh.Session, space: str, name: str) -> zenoh.LivelinessToken:
    """Declare that agent `name` is alive in `space` until the token is undeclared."""
    return session.liveliness().declare_token(agent_key(space, name))


def alive_agents(session: zenoh.Session, space: str, timeout: float = 2.0) -> list[str]:
    """Return the names of the agents alive in `space` now (a fleet's may be many hundreds).

    Raises:
        SpaceTimeout: Zenoh did not end the get within `timeout` and a grace (`every_reply`).
    """
    replies = every_reply(session.liveliness().get, agents_key(space), timeout)
    return sorted(
        keys.unescape(str(r.ok.key_expr).rsplit("/", 1)[1]) for r in replies if r.ok is not None
    )


def watch_agents(
    session: zenoh.Session, space: str, callback: Callable[[str, bool], None]
) -> zenoh.Subscriber:
    """Call `callback(name, alive)` as agents come and go (from a Zenoh thread: don't block).

    Agents already alive are reported first.
    """

    def on_sample(sample: zenoh.Sample) -> None:
        name = keys.unescape(str(sample.key_expr).rsplit("/", 1)[1])
        callback(name, sample.kind == zenoh.SampleKind.PUT)

    return session.liveliness().declare_subscriber(agents_key(space), on_sample, history=True)
