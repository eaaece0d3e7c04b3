"""Test what kind of term a value is: `isLiteral notLiteral isBNode notBNode isDType notDType
bound unbound`."""

from __future__ import annotations

from typing import ClassVar

from rdflib import XSD, BNode, Literal, URIRef

from space.reasoning.builtins.base import Args, Builtin, Context


class _Kind(Builtin):
    """Accept when the argument is (or, negated, is not) of one kind of term."""

    arity = (1, 1)
    kind: ClassVar[type]
    negated: ClassVar[bool] = False

    def run(self, ctx: Context, args: Args) -> Args | None:
        is_kind = isinstance(ctx.terms.term(args[0]), self.kind)  # type: ignore[arg-type]
        return args if is_kind != self.negated else None


class IsLiteral(_Kind):
    """Accept a literal."""

    name = "isLiteral"
    kind = Literal


class NotLiteral(_Kind):
    """Accept anything but a literal."""

    name = "notLiteral"
    kind = Literal
    negated = True


class IsBNode(_Kind):
    """Accept a blank node."""

    name = "isBNode"
    kind = BNode


class NotBNode(_Kind):
    """Accept anything but a blank node."""

    name = "notBNode"
    kind = BNode
    negated = True


def _has_datatype(literal: object, datatype: object) -> bool:
    if not isinstance(literal, Literal) or not isinstance(datatype, URIRef):
        return False
    if literal.datatype is None:
        return datatype in (XSD.string, URIRef(str(XSD.string))) and literal.language is None
    return literal.datatype == datatype and literal.ill_typed is not True


class IsDType(Builtin):
    """Accept a literal that is a well-formed value of the given datatype."""

    name = "isDType"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        literal, datatype = (ctx.terms.term(i) for i in args)  # type: ignore[arg-type]
        return args if _has_datatype(literal, datatype) else None


class NotDType(Builtin):
    """Accept anything that is not a well-formed value of the given datatype."""

    name = "notDType"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        literal, datatype = (ctx.terms.term(i) for i in args)  # type: ignore[arg-type]
        return None if _has_datatype(literal, datatype) else args


class Bound(Builtin):
    """Accept when every argument is bound."""

    name = "bound"
    arity = (1, None)
    deferred = True

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args if None not in args else None


class Unbound(Builtin):
    """Accept when no argument is bound."""

    name = "unbound"
    arity = (1, None)
    deferred = True

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args if all(a is None for a in args) else None


BUILTINS: tuple[Builtin, ...] = (
    IsLiteral(),
    NotLiteral(),
    IsBNode(),
    NotBNode(),
    IsDType(),
    NotDType(),
    Bound(),
    Unbound(),
)
