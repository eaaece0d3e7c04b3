"""The store's half of a secure space's policy: the triples each identity may write.

A secure router lets each identity write (and take) only on keys that end
with its certificate's name, `@/write/<CN>` and `@/query/<CN>`, and lets only
servers and operators use the bare `@/write`. So the store knows who sent a
write; this module says whether the policy allows what it changes, which
Zenoh cannot see: a robot's agents change their robot's things only, the HMI
and the fleet monitor their own predicates only, nobody but a reasoner the
inferred graph.

What a robot owns is read from the space as it is, never from the write
itself: a robot's agents cannot add a link that would make another robot's
device theirs, nor use the ontology's own words (`owl:sameAs` would make
one robot another); a robot's makeup is an operator's to write.
"""

from __future__ import annotations

from collections.abc import Callable

import pyoxigraph as ox
from rdflib import OWL, RDFS

from space._policy import Policy, Role
from space.errors import QueryError
from space.store import oxterms
from space.store.intake import WriteRequest
from space.store.oxterms import OxTerm, OxTriple

_SCHEMA = (str(OWL), str(RDFS))  # the ontology's own words, not a robot's to use

Holds = Callable[[OxTriple], bool]  # whether the space's asserted graph holds a triple now
Compact = Callable[[str], str | None]  # an IRI as `pfx:local`, or None


class Refused(QueryError):
    """The policy does not let this identity write (or take) these triples."""


def writer_of(key: str) -> str | None:
    """Return the identity a `<root>/<space>/@/<service>/<CN>` key names; None for a bare key."""
    parts = key.split("/")
    return parts[4] if len(parts) == 5 else None


class WriteGuard:
    """Check writes and takes against a policy; used by the store's writer thread only."""

    def __init__(self, policy: Policy) -> None:
        self.policy = policy
        # The policy's IRIs as the database's terms, converted once.
        self._robot_of = {n: ox.NamedNode(str(r)) for n, r in policy.robot_of.items()}
        self._predicates = {
            n: frozenset(ox.NamedNode(str(p)) for p in ps) for n, ps in policy.predicates.items()
        }
        self._links = tuple(ox.NamedNode(str(p)) for p in policy.links)
        self._backlinks = tuple(ox.NamedNode(str(p)) for p in policy.backlinks)
        self._makeup = frozenset((*self._links, *self._backlinks))

    def refusal(
        self,
        writer: str | None,
        req: WriteRequest,
        holds: Holds,
        compact: Compact,
        *,
        take: bool = False,
    ) -> str | None:
        """Return why `writer` may not apply `req` to the space, or None if it may.

        `holds` says what the space's asserted graph holds before `req` (a robot's
        things are read from there, never from the write itself); `compact` names
        IRIs in the refusal. `writer` None is the bare key, which the routers leave
        to servers and operators; a take on the bare `@/query` (open to every
        reader) is refused.
        """
        if writer is None:
            return "refused: a take must name its taker (@/query/<CN>)" if take else None
        role = self.policy.role(writer)
        if role is None:
            return f"refused {writer}: not in the policy, or revoked"
        if role in (Role.SERVER, Role.OPERATOR, Role.REASONER):
            return None
        if req.inferred_added or req.inferred_removed:
            return f"refused {writer}: only reasoners write inferred triples"
        changed = [*req.removed, *req.added]
        if role is Role.WRITER:
            allowed = self._predicates.get(writer, frozenset())
            for s, p, _o in changed:
                if p not in allowed:
                    return (
                        f"refused {writer}: may not write {_name(p, compact)} "
                        f"(of {_name(s, compact)})"
                    )
            return None
        robot = self._robot_of[writer]  # a robot agent's, or a robot router's own
        for _s, p, _o in req.added:
            if p in self._makeup or (isinstance(p, ox.NamedNode) and p.value.startswith(_SCHEMA)):
                return f"refused {writer}: may not add {_name(p, compact)} (an operator's to write)"
        for s, p, _o in changed:
            if not self._owns(robot, s, holds):
                return (
                    f"refused {writer}: may not write {_name(s, compact)} {_name(p, compact)}, "
                    f"not a thing of {_name(robot, compact)}"
                )
        return None

    def _owns(self, robot: OxTerm, subject: OxTerm, holds: Holds) -> bool:
        """Say whether `subject` is `robot`, linked from it, or links to it, in the space."""
        if subject == robot:
            return True
        if any(holds((robot, link, subject)) for link in self._links):
            return True
        return any(holds((subject, b, robot)) for b in self._backlinks)


def _name(term: OxTerm, compact: Compact) -> str:
    if isinstance(term, ox.NamedNode) and not term.value.startswith(oxterms.SKOLEM):
        return compact(term.value) or f"<{term.value}>"
    return oxterms.text(term)
