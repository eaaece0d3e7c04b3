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

from rdflib import OWL, RDFS, Graph
from rdflib.term import Node

from space import keys
from space._policy import Policy, Role
from space.changeset import Changeset
from space.store.state import SpaceState

_SCHEMA = (str(OWL), str(RDFS))  # the ontology's own words, not a robot's to use


def writer_of(key: str) -> str | None:
    """Return the identity a `<root>/<space>/@/<service>/<CN>` key names; None for a bare key."""
    parts = key.split("/")
    return parts[4] if len(parts) == 5 else None


class WriteGuard:
    """Check changesets against a policy; used by the store's worker thread only."""

    def __init__(self, policy: Policy) -> None:
        self.policy = policy

    def refusal(
        self, writer: str | None, state: SpaceState, cs: Changeset, *, take: bool = False
    ) -> str | None:
        """Return why `writer` may not apply `cs` to `state`, or None if it may.

        `writer` None is the bare key, which the routers leave to servers and
        operators; a take on the bare `@/query` (open to every reader) is refused.
        """
        if writer is None:
            return "refused: a take must name its taker (@/query/<CN>)" if take else None
        role = self.policy.role(writer)
        if role is None:
            return f"refused {writer}: not in the policy, or revoked"
        if role in (Role.SERVER, Role.OPERATOR, Role.REASONER):
            return None
        if cs.inferred_added or cs.inferred_removed:
            return f"refused {writer}: only reasoners write inferred triples"
        show = state.prefixes.compact
        changed = [*cs.removed, *cs.added]
        if role is Role.WRITER:
            allowed = self.policy.predicates.get(writer, frozenset())
            for s, p, _o in changed:
                if p not in allowed:
                    return f"refused {writer}: may not write {_name(p, show)} (of {_name(s, show)})"
            return None
        robot = self.policy.robot_of[writer]  # a robot agent's, or a robot router's own
        makeup = {*self.policy.links, *self.policy.backlinks}
        for _s, p, _o in cs.added:
            if p in makeup or str(p).startswith(_SCHEMA):
                return f"refused {writer}: may not add {_name(p, show)} (an operator's to write)"
        asserted = state.graphs[keys.ASSERTED]
        for s, p, _o in changed:
            if not self._owns(robot, s, asserted):
                return (
                    f"refused {writer}: may not write {_name(s, show)} {_name(p, show)}, "
                    f"not a thing of {_name(robot, show)}"
                )
        return None

    def _owns(self, robot: Node, subject: Node, asserted: Graph) -> bool:
        """Say whether `subject` is `robot`, linked from it, or links to it, in the space."""
        if subject == robot:
            return True
        if any((robot, link, subject) in asserted for link in self.policy.links):
            return True
        return any((subject, b, robot) in asserted for b in self.policy.backlinks)


def _name(term: Node, compact: Callable[[str], str | None]) -> str:
    return compact(str(term)) or f"<{term}>"
