"""Describe what an update changed: the `Delta` an engine returns, and `why` answers."""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import NamedTuple

from space.terms import Triple


class Origin(enum.Enum):
    """Whether a triple is in the state because someone asserted it or a rule inferred it."""

    ASSERTED = "asserted"
    INFERRED = "inferred"


class Change(NamedTuple):
    """One triple that appeared in or left the state, and its origin at that moment."""

    triple: Triple
    origin: Origin


@dataclass(frozen=True)
class Firing:
    """One firing of a production rule: what matched, and what it changed."""

    rule: str
    triggers: tuple[Triple, ...]
    asserted: tuple[Triple, ...]
    retracted: tuple[Triple, ...]


@dataclass(frozen=True)
class Why:
    """Why a triple holds: asserted by a caller, or by a rule from premises.

    `rule` is None for a triple a caller asserted. A production rule's head is
    asserted too, and also names its rule and premises.
    """

    asserted: bool
    rule: str | None = None
    premises: tuple[Triple, ...] = ()


@dataclass(frozen=True)
class Delta:
    """The net change of one `load` or `apply`.

    `added` and `removed` cover the whole state. For a caller that keeps asserted
    and inferred triples apart (the reasoner agent), `asserted_added` and
    `asserted_removed` are the changes production rules made to the asserted
    state beyond the caller's own; `inferred_added` and `inferred_removed` are
    the changes to what is inferred and not asserted. `firings` lists the
    production rules that fired, in order.
    """

    added: tuple[Change, ...] = ()
    removed: tuple[Change, ...] = ()
    asserted_added: tuple[Triple, ...] = ()
    asserted_removed: tuple[Triple, ...] = ()
    inferred_added: tuple[Triple, ...] = ()
    inferred_removed: tuple[Triple, ...] = ()
    firings: tuple[Firing, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.added or self.removed or self.asserted_added or self.asserted_removed)
