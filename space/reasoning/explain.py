"""Turn an engine's derivations into explanation trees, with each rule's name and comment.

`RuleEngine.why` says, for one triple, which rule concluded it from which
premises. `Explainer` follows that down to the triples nobody derived, names
each rule with the comment written above it in its file (the rules files are
read again for that: the parser keeps locations, not comments), and asks a
caller-given function who wrote each asserted triple.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from functools import lru_cache
from pathlib import Path

from space.explanation import ASSERTED, GONE, INFERRED, Explanation, Written
from space.reasoning.rules import Rule
from space.terms import Triple

MAX_DEPTH = 16

# What the OWL 2 RL rules (named as in the OWL 2 specification, table 4 to 9) conclude.
OWL_RL = {
    "cax-sco": "OWL RL: an instance of a class is an instance of its superclasses",
    "cax-eqc1": "OWL RL: an instance of a class is an instance of its equivalent classes",
    "cax-eqc2": "OWL RL: an instance of a class is an instance of its equivalent classes",
    "prp-dom": "OWL RL: the subject of a property is an instance of its domain",
    "prp-rng": "OWL RL: the object of a property is an instance of its range",
    "prp-spo1": "OWL RL: a sub-property's statements hold for its super-property",
    "prp-inv1": "OWL RL: a property's statements hold reversed for its inverse",
    "prp-inv2": "OWL RL: a property's statements hold reversed for its inverse",
    "prp-symp": "OWL RL: a symmetric property holds both ways",
    "prp-trp": "OWL RL: a transitive property chains",
    "eq-sym": "OWL RL: sameAs is symmetric",
    "eq-trans": "OWL RL: sameAs is transitive",
}


@lru_cache(maxsize=64)
def _lines(path: str, mtime: float) -> tuple[str, ...]:
    """Return a file's lines (cached per modification time: a reload re-reads it)."""
    try:
        return tuple(Path(path).read_text(encoding="utf-8").splitlines())
    except (OSError, UnicodeDecodeError):
        return ()


def comment_above(path: str, line: int) -> str | None:
    """Return the comment lines written just above `line` of a file (1-based), joined.

    A blank line ends the comment: a section header further up is not the rule's.
    """
    try:
        mtime = Path(path).stat().st_mtime
    except OSError:
        return None
    lines = _lines(path, mtime)
    found: list[str] = []
    index = line - 2
    while 0 <= index < len(lines) and lines[index].lstrip().startswith("#"):
        found.append(lines[index].lstrip().lstrip("#").strip())
        index -= 1
    text = " ".join(reversed([f for f in found if f and not set(f) <= set("-=#")]))
    return text or None


class Explainer:
    """Explain triples from an engine's `why`, rule notes and a writer lookup.

    Args:
        why: the engine's `why` (a triple -> `Why` or None).
        rules: the engine's rules, for their comments and locations.
        written: returns who wrote each of the given asserted triples (those it knows).
    """

    def __init__(
        self,
        why: Callable[[Triple], object],
        rules: Sequence[Rule],
        written: Callable[[Iterable[Triple]], dict[Triple, Written]],
    ) -> None:
        self._why = why
        self._written = written
        self._notes: dict[str, tuple[str | None, str | None]] = {}
        for rule in rules:
            if rule.where is not None:
                comment = comment_above(rule.where.file, rule.where.line)
                self._notes[rule.label] = (comment, f"{rule.where.file}:{rule.where.line}")
            else:
                self._notes[rule.label] = (None, None)

    def explain(self, triples: Iterable[Triple]) -> list[Explanation]:
        """Return one tree per triple that holds (the others are left out).

        Within one tree a triple is explained once; where it comes again, it is
        marked `repeated` without its premises.
        """
        drafts = []
        for triple in triples:
            draft = self._draft(triple, set(), 0)
            if draft is not None:
                drafts.append(draft)
        asserted = [d.triple for tree in drafts for d in _nodes(tree) if d.holds == ASSERTED]
        writers = self._written(dict.fromkeys(asserted)) if asserted else {}
        return [_with_writers(tree, writers) for tree in drafts]

    def _draft(self, triple: Triple, seen: set[Triple], depth: int) -> Explanation | None:
        why = self._why(triple)
        if why is None:
            return Explanation(triple, GONE) if depth else None
        holds = ASSERTED if why.asserted else INFERRED  # type: ignore[attr-defined]
        rule: str | None = why.rule  # type: ignore[attr-defined]
        if triple in seen:
            return Explanation(triple, holds, rule, repeated=True)
        seen.add(triple)
        if rule is None:
            return Explanation(triple, holds)
        comment, where = self._notes.get(rule, (OWL_RL.get(rule), None))
        premises = []
        if depth < MAX_DEPTH:
            for premise in why.premises:  # type: ignore[attr-defined]
                node = self._draft(premise, seen, depth + 1)
                if node is not None:
                    premises.append(node)
        return Explanation(triple, holds, rule, comment, where, tuple(premises))


def _nodes(tree: Explanation) -> Iterable[Explanation]:
    return (node for _depth, node in tree.walk())


def _with_writers(tree: Explanation, writers: dict[Triple, Written]) -> Explanation:
    premises = tuple(_with_writers(p, writers) for p in tree.premises)
    written = writers.get(tree.triple) if tree.holds == ASSERTED else None
    if written is None and premises == tree.premises:
        return tree
    return Explanation(
        tree.triple,
        tree.holds,
        tree.rule,
        tree.comment,
        tree.where,
        premises,
        written,
        tree.repeated,
    )
