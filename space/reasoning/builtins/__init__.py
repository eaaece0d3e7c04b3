"""The builtins of the Jena rule language, one small class each, and their registry."""

from __future__ import annotations

from space.reasoning.builtins import (
    actions,
    arithmetic,
    compare,
    kinds,
    listmap,
    lists,
    nodes,
    strings,
    tabling,
)
from space.reasoning.builtins.base import Args, Builtin, Context, Effect, Place, Registry

__all__ = ["Args", "Builtin", "Context", "Effect", "Place", "Registry", "default_registry"]


def default_registry() -> Registry:
    """Return a new registry holding every standard builtin."""
    return Registry(
        (
            *compare.BUILTINS,
            *arithmetic.BUILTINS,
            *strings.BUILTINS,
            *kinds.BUILTINS,
            *nodes.BUILTINS,
            *actions.BUILTINS,
            *lists.BUILTINS,
            *tabling.BUILTINS,
            *listmap.BUILTINS,
        )
    )
