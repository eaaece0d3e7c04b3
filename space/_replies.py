"""Every reply of a Zenoh get that may have many: kept by a callback, its end awaited with a bound.

Zenoh's default handler is a FIFO channel of 256 replies: past that, Zenoh's
own thread waits until the caller takes some, and a CI run once hung for good
in such a get (a wildcard over a store shared by many tests). A callback
keeps each reply as it comes (Zenoh never waits on us), and the get's end (its
callback dropped) is awaited no longer than its timeout and a grace.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import zenoh

from space.errors import SpaceTimeout

GRACE = 5.0  # seconds past a get's own timeout before it is given up as stuck


def every_reply(
    get: Callable[..., Any], selector: str, timeout: float, **options: Any
) -> list[zenoh.Reply]:
    """Return every reply of `get(selector, ..., timeout=timeout, **options)`.

    `get` is a session's `get` or its liveliness' (`session.liveliness().get`).

    Raises:
        SpaceTimeout: the get was not over `GRACE` seconds after its timeout.
    """
    replies: list[zenoh.Reply] = []
    over = threading.Event()
    get(selector, zenoh.handlers.Callback(replies.append, over.set), timeout=timeout, **options)
    if not over.wait(timeout + GRACE):
        raise SpaceTimeout(f"the get of {selector} was not over {GRACE:g} s after its timeout")
    return list(replies)
