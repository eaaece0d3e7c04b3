"""Keep what a process builds at start out of the garbage collector's full walks.

A full collection walks every tracked object: in a process holding a space (the
store's state, an agent's view, the reasoner's engine) one took 20-60 ms, and it
landed on whatever change was in flight (the tail of the end-to-end latency).
What a process builds at start (rules, ontology, the view of the space) lives as
long as the process, so it is frozen out of those walks once, after start.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager


def freeze_startup() -> None:
    """Collect the start's garbage, then freeze every object alive (`gc.freeze`).

    Call once, when the process has built its long-lived state. Objects made
    later are collected as usual.
    """
    gc.collect()
    gc.freeze()


def refreeze() -> None:
    """Freeze again after replacing long-lived state (a rules reload, a copied space).

    Frozen objects are never collected: the ones the replaced state leaves in
    reference cycles are unfrozen first, so this collection frees them.
    """
    gc.unfreeze()
    freeze_startup()


@contextmanager
def collector_paused() -> Iterator[None]:
    """Pause the cyclic collector (if it runs) while a block builds long-lived objects.

    Each collection during a build walks what it built so far again: an engine
    for 2,000 rules ran 8 full collections while it was built.
    """
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()
