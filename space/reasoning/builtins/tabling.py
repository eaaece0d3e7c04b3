"""Jena's backward-engine directives: `table tableAll` (no-ops here) and `hide`.

`table` asks Jena's backward engine to memoize goals; forward evaluation keeps
every conclusion anyway, so both are accepted and do nothing. `hide(n)` keeps every
triple with `n` as subject, predicate or object out of what the engine lists and
reports, as Jena's FBRuleInfGraph filters its answers; rules still see them.
"""

from __future__ import annotations

from space.reasoning.builtins.base import Args, Builtin, Context, Place


class Table(Builtin):
    """Accept and ignore: forward evaluation already keeps every goal's answers."""

    name = "table"
    arity = (0, None)
    places = Place.BODY | Place.HEAD
    deferred = True

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args


class TableAll(Table):
    """Accept and ignore, as `table`."""

    name = "tableAll"


class Hide(Builtin):
    """Keep the triples that name the given nodes out of the engine's listings."""

    name = "hide"
    arity = (1, None)
    places = Place.BODY | Place.HEAD
    deferred = True

    def run(self, ctx: Context, args: Args) -> Args | None:
        ctx.terms.hidden.update(a for a in args if a is not None)
        return args


BUILTINS: tuple[Builtin, ...] = (Table(), TableAll(), Hide())
