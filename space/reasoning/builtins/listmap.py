"""Jena's head builtins that assert a triple per list entry: `listMapAsSubject
listMapAsObject assertDisjointPairs`. The rules parser rewrites them into rules
(`space.reasoning.listmaps`); they never run themselves."""

from __future__ import annotations

from space.reasoning.builtins.base import Args, Builtin, Context, Place
from space.reasoning.errors import RuleError


class ListMap(Builtin):
    """A head builtin the parser turns into rules (see the module); never run itself."""

    places = Place.HEAD

    def act(self, ctx: Context, args: Args) -> None:
        raise RuleError(f"{self.name}() runs only in rules read by the rules parser")


class ListMapAsSubject(ListMap):
    """Assert `(x p o)` for each entry `x` of the list."""

    name = "listMapAsSubject"
    arity = (3, 3)


class ListMapAsObject(ListMap):
    """Assert `(s p x)` for each entry `x` of the list."""

    name = "listMapAsObject"
    arity = (3, 3)


class AssertDisjointPairs(ListMap):
    """Assert `(x owl:differentFrom y)` for each two distinct entries of the list."""

    name = "assertDisjointPairs"
    arity = (1, 1)


BUILTINS: tuple[Builtin, ...] = (ListMapAsSubject(), ListMapAsObject(), AssertDisjointPairs())
