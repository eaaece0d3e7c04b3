"""Act on the state: `print remove drop noValue`, the builtins that are not monotonic."""

from __future__ import annotations

from space.reasoning.builtins.base import Args, Builtin, Context, Effect, Place
from space.reasoning.terms import FunctorValue


def _show(ctx: Context, i: int | None) -> str:
    if i is None:
        return "?"
    term = ctx.terms.term(i)
    if isinstance(term, FunctorValue):
        return f"{term.name}({', '.join(_show(ctx, a) for a in term.args)})"
    return term.n3()


class Print(Builtin):
    """Print the arguments, in a body (always accepts) or a head."""

    name = "print"
    arity = (0, None)
    places = Place.BODY | Place.HEAD
    deferred = True

    def run(self, ctx: Context, args: Args) -> Args | None:
        ctx.printer(" ".join(_show(ctx, a) for a in args))
        return args


class Remove(Builtin):
    """Retract the triples matched by the given body items (0-based); other rules see it."""

    name = "remove"
    arity = (1, None)
    places = Place.HEAD
    monotonic = False
    effect = Effect.REMOVE


class Drop(Builtin):
    """Delete the triples matched by the given body items (0-based) without telling rules."""

    name = "drop"
    arity = (1, None)
    places = Place.HEAD
    monotonic = False
    effect = Effect.DROP


class NoValue(Builtin):
    """Accept when no triple matches `(s p)` or `(s p o)`; unbound arguments match anything."""

    name = "noValue"
    arity = (2, 3)
    monotonic = False
    deferred = True

    def run(self, ctx: Context, args: Args) -> Args | None:
        s, p, o = (*args, None) if len(args) == 2 else args
        return None if ctx.store.exists(s, p, o) else args


BUILTINS: tuple[Builtin, ...] = (Print(), Remove(), Drop(), NoValue())
