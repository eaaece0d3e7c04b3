"""Model the rules of the Jena rule language: terms, triple patterns, builtin calls, rules.

The model is plain immutable data with rdflib terms for constants, so the parser,
the OWL RL compiler and a test can all build rules the same way, and the engine
compiles them without caring where they came from.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from rdflib.term import Node

if TYPE_CHECKING:
    from space.reasoning.builtins import Builtin


@dataclass(frozen=True)
class Location:
    """Where a rule or one of its items was written."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


@dataclass(frozen=True)
class Var:
    """A rule variable such as `?x`."""

    name: str

    def __str__(self) -> str:
        return f"?{self.name}"


@dataclass(frozen=True)
class Functor:
    """A structured value `name(arg, ...)`, seen only by rules (never in the output graph)."""

    name: str
    args: tuple[Term, ...]

    def __str__(self) -> str:
        return f"{self.name}({', '.join(show(a) for a in self.args)})"


Term = Node | Var | Functor


@dataclass(frozen=True)
class Pattern:
    """A triple pattern `(s p o)` of a body (to match) or a head (to assert)."""

    s: Term
    p: Term
    o: Term
    where: Location | None = None

    @property
    def terms(self) -> tuple[Term, Term, Term]:
        """Return the subject, predicate and object."""
        return (self.s, self.p, self.o)

    def __str__(self) -> str:
        return f"({show(self.s)} {show(self.p)} {show(self.o)})"


@dataclass(frozen=True)
class Call:
    """A builtin call such as `notEqual(?speed, 'low')` or `drop(6)`."""

    builtin: Builtin
    args: tuple[Term, ...]
    where: Location | None = None

    @property
    def name(self) -> str:
        """Return the builtin's name."""
        return self.builtin.name

    def __str__(self) -> str:
        return f"{self.name}({', '.join(show(a) for a in self.args)})"


Item = Pattern | Call


@dataclass(frozen=True)
class Rule:
    """A forward rule `[name: body -> head]`; body items are indexed from 0, calls included.

    `backward` marks a rule written `[head <- body]`, which this engine runs forward;
    `shared_name` one whose name another rule of its set has (Jena allows it).
    """

    name: str | None
    body: tuple[Item, ...]
    head: tuple[Item, ...]
    where: Location | None = None
    backward: bool = False
    shared_name: bool = False

    @property
    def label(self) -> str:
        """Return the name (with `file:line` when another rule has it too), or where it is."""
        if self.name:
            if self.shared_name and self.where:
                return f"{self.name} ({self.where.file}:{self.where.line})"
            return self.name
        return f"<rule at {self.where}>" if self.where else "<unnamed rule>"

    def __str__(self) -> str:
        body = ", ".join(str(i) for i in self.body)
        head = ", ".join(str(i) for i in self.head)
        prefix = f"{self.name}: " if self.name else ""
        return f"[{prefix}{body} -> {head}]"


def show(term: Term) -> str:
    """Return a term as it would be written in a rules file."""
    if isinstance(term, Var | Functor):
        return str(term)
    return term.n3()


def variables(term: Term) -> list[Var]:
    """Return the variables of a term, functor arguments included, in order."""
    if isinstance(term, Var):
        return [term]
    if isinstance(term, Functor):
        return [v for a in term.args for v in variables(a)]
    return []
