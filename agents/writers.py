"""Who wrote each fact the reasoner holds, for its answers to `why`.

`Writers` remembers, for each asserted triple, the changeset that last added
it: from the changes the reasoner applies, and for what it loaded at start
from the store's log, read backwards on demand. It keeps the triples as the
reasoner gets them, N-Triples texts.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable

from space import Changeset, SpaceError, TextTriple, Triple, Written, text_of

log = logging.getLogger("tspace.why")

LOG_CHUNK = 500  # changesets read from the store's log per request
LOG_SCAN_MAX = 50_000  # changesets read at most to answer one why


class Writers:
    """Who last wrote each asserted triple.

    Args:
        history: reads the store's log (`TripleSpace.history`), `(first, last)`.
    """

    def __init__(self, history: Callable[[int, int], list[Changeset]]) -> None:
        self._history = history
        self._by: dict[TextTriple, Written] = {}
        self._unread = 0  # the log up to this seq holds writers not yet read

    def loaded(self, seq: int) -> None:
        """Say that the state up to `seq` was loaded without its writers."""
        self._unread = max(self._unread, seq)

    def note(
        self,
        cs: Changeset,
        added: list[TextTriple] | None = None,
        removed: list[TextTriple] | None = None,
    ) -> None:
        """Remember who wrote the asserted triples a changeset adds; forget the removed ones.

        The changeset's triples are N-Triples texts (`Changeset.texts`). `added`,
        `removed`: those of its triples to note, when not all (the reasoner's answers
        leave out their firing records, half of an answer that fired 200 rules).
        """
        by = self._by
        for t in cs.removed if removed is None else removed:
            by.pop(t, None)
        added = cs.added if added is None else added
        if added:
            written = Written(cs.agent, cs.timestamp, cs.id, cs.seq)
            for t in added:
                by[t] = written

    def lookup(self, triples: Iterable[Triple]) -> dict[Triple, Written]:
        """Return the writers known of `triples`, reading older log entries for the others.

        Blocks on the store for those (the first `why` after a start); a store that
        does not answer leaves them unknown, it is logged.
        """
        wanted = {t: text_of(t) for t in triples}  # as they are kept
        missing = {t for t in wanted.values() if t not in self._by}
        scanned = 0
        while missing and self._unread >= 1 and scanned < LOG_SCAN_MAX:
            first = max(1, self._unread - LOG_CHUNK + 1)
            try:
                changes = self._history(first, self._unread)
            except SpaceError as exc:
                log.warning("writers not read from the store's log: %s", exc)
                break
            for cs in reversed(changes):
                written = Written(cs.agent, cs.timestamp, cs.id, cs.seq)
                for t in cs.added:  # a later write, noted already, wins
                    self._by.setdefault(text_of(t), written)
            scanned += self._unread - first + 1
            self._unread = first - 1
            missing = {t for t in missing if t not in self._by}
        return {t: self._by[text] for t, text in wanted.items() if text in self._by}
