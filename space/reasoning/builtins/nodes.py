"""Make new nodes: `makeTemp makeSkolem makeInstance now`."""

from __future__ import annotations

import hashlib
from datetime import UTC, datetime

from rdflib import BNode, Literal

from space.reasoning.builtins.base import Args, Builtin, Context
from space.terms import to_nt


def _skolem(ctx: Context, tag: str, ids: Args) -> int:
    """Return a blank node that is the same for the same arguments, in any run."""
    text = "\n".join([tag, *(to_nt(ctx.terms.term(i)) for i in ids)])  # type: ignore[arg-type]
    return ctx.terms.id(BNode("sk" + hashlib.sha1(text.encode()).hexdigest()[:24]))


def _bind(args: Args, position: int, value: int) -> Args | None:
    if args[position] is None:
        return (*args[:position], value, *args[position + 1 :])
    return args if args[position] == value else None


class MakeTemp(Builtin):
    """Bind the argument to a new blank node at each match."""

    name = "makeTemp"
    arity = (1, 1)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({0})

    def run(self, ctx: Context, args: Args) -> Args | None:
        return _bind(args, 0, ctx.fresh_bnode())


class MakeSkolem(Builtin):
    """Bind the first argument to a blank node determined by the other arguments."""

    name = "makeSkolem"
    arity = (1, None)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({0})

    def run(self, ctx: Context, args: Args) -> Args | None:
        return _bind(args, 0, _skolem(ctx, "skolem", args[1:]))


class MakeInstance(Builtin):
    """Bind the last argument to the blank node that is the value of property ?p on ?x.

    Called as `makeInstance(?x, ?p, ?v)` or `makeInstance(?x, ?p, ?type, ?v)`;
    the same arguments give the same node.
    """

    name = "makeInstance"
    arity = (3, 4)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({nargs - 1})

    def run(self, ctx: Context, args: Args) -> Args | None:
        return _bind(args, len(args) - 1, _skolem(ctx, "instance", args[:-1]))


class Now(Builtin):
    """Bind the argument to the current time as an xsd:dateTime."""

    name = "now"
    arity = (1, 1)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({0})

    def run(self, ctx: Context, args: Args) -> Args | None:
        return _bind(args, 0, ctx.terms.id(Literal(datetime.now(UTC))))


BUILTINS: tuple[Builtin, ...] = (MakeTemp(), MakeSkolem(), MakeInstance(), Now())
