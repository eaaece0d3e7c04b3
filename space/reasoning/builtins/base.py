"""Define what a builtin is, what it may see when it runs, and the registry that holds them."""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from rdflib import BNode

if TYPE_CHECKING:
    from space.reasoning.terms import TermTable
    from space.reasoning.triples import TripleStore

Args = tuple[int | None, ...]


class Place(enum.Flag):
    """Where a builtin may be written in a rule."""

    BODY = enum.auto()
    HEAD = enum.auto()


class Effect(enum.Enum):
    """What a head builtin does to the state besides returning."""

    NONE = "none"
    DROP = "drop"
    REMOVE = "remove"


@dataclass
class Context:
    """Give builtins the terms, the current triples and a place to print."""

    terms: TermTable
    store: TripleStore
    printer: Callable[[str], None] = print

    def fresh_bnode(self) -> int:
        """Return the id of a new blank node."""
        return self.terms.id(BNode())


class Builtin:
    """Describe one builtin: its name, arity, where it may go, and how it runs.

    Subclasses set the class attributes and override `run` (body) or `act` (head).
    A body call runs as soon as its inputs are bound; a `deferred` one runs after
    every pattern, with whatever is bound by then (`bound`, `noValue`).
    `run` gets the encoded arguments, None for a variable not bound yet, and
    returns them with the outputs bound, or None when the test fails.
    """

    name: ClassVar[str]
    arity: ClassVar[tuple[int, int | None]]
    places: ClassVar[Place] = Place.BODY
    monotonic: ClassVar[bool] = True
    effect: ClassVar[Effect] = Effect.NONE
    deferred: ClassVar[bool] = False

    def outputs(self, nargs: int) -> frozenset[int]:
        """Return the argument positions this builtin binds when they are unbound."""
        return frozenset()

    def check(self, args: tuple[object, ...]) -> str | None:
        """Return why the call's constant arguments cannot work (checked on load), or None."""
        return None

    def accepts(self, nargs: int) -> bool:
        """Tell whether a call with `nargs` arguments is well formed."""
        low, high = self.arity
        return nargs >= low and (high is None or nargs <= high)

    def run(self, ctx: Context, args: Args) -> Args | None:
        """Evaluate the call in a body; return the bound arguments, or None to reject."""
        raise NotImplementedError(self.name)

    def act(self, ctx: Context, args: Args) -> None:
        """Perform the call in a head (only builtins whose places include HEAD)."""
        self.run(ctx, args)

    def __repr__(self) -> str:
        return f"<builtin {self.name}>"


class Registry:
    """Hold the builtins a parser and an engine may use, by name.

    A registry is passed in, never global, so a test or an agent can add its own
    builtins without changing anyone else's.
    """

    def __init__(self, builtins: Iterable[Builtin] = ()) -> None:
        self._by_name: dict[str, Builtin] = {}
        for builtin in builtins:
            self.register(builtin)

    def register(self, builtin: Builtin) -> None:
        """Add a builtin, replacing any other of the same name."""
        self._by_name[builtin.name] = builtin

    def get(self, name: str) -> Builtin | None:
        """Return the builtin called `name`, or None."""
        return self._by_name.get(name)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __iter__(self) -> Iterator[Builtin]:
        return iter(self._by_name.values())
