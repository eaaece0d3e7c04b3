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


class TripleChange(NamedTuple):
    """One triple that appeared in or left the state, and its origin at that moment."""

    triple: Triple
    origin: Origin


NEW_FIRING = tuple.__new__


class Firing(tuple):
    """One firing of a production rule: what matched (`triggers`), and what it changed.

    The triples are decoded when first read: most callers only count firings. A tuple
    `(rule, triggers, asserted, retracted, decode)`, the triples encoded, made in C
    (`NEW_FIRING(Firing, (...))`): a Python `__init__` was a tenth of a short firing.
    """

    __slots__ = ()

    @property
    def rule(self) -> str:
        """Return the label of the rule that fired."""
        return self[0]

    @property
    def triggers(self) -> tuple[Triple, ...]:
        """Return the triples the rule's body matched, in body order."""
        return tuple(map(self[4], self[1]))

    @property
    def asserted(self) -> tuple[Triple, ...]:
        """Return the triples the rule's head asserted."""
        return tuple(map(self[4], self[2]))

    @property
    def retracted(self) -> tuple[Triple, ...]:
        """Return the triples the rule dropped or removed."""
        return tuple(map(self[4], self[3]))

    def __repr__(self) -> str:
        return f"Firing({self.rule!r}, triggers={self.triggers}, asserted={self.asserted})"


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

    added: tuple[TripleChange, ...] = ()
    removed: tuple[TripleChange, ...] = ()
    asserted_added: tuple[Triple, ...] = ()
    asserted_removed: tuple[Triple, ...] = ()
    inferred_added: tuple[Triple, ...] = ()
    inferred_removed: tuple[Triple, ...] = ()
    firings: tuple[Firing, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.added or self.removed or self.asserted_added or self.asserted_removed)
