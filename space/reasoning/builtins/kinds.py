"""Test what kind of term a value is: `isLiteral notLiteral isBNode notBNode isDType notDType
isFunctor notFunctor bound unbound`, and count a subject's literal values."""

from __future__ import annotations

from typing import ClassVar

from rdflib import RDFS, XSD, BNode, Literal, URIRef

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
    if datatype == RDFS.Literal:  # every literal is an rdfs:Literal, as in Jena
        return True
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


class IsFunctor(Builtin):
    """Accept a functor value (`f(a, b)` made by a rule head)."""

    name = "isFunctor"
    arity = (1, 1)

    def run(self, ctx: Context, args: Args) -> Args | None:
        return args if args[0] in ctx.terms.functors else None


class NotFunctor(Builtin):
    """Accept anything but a functor value."""

    name = "notFunctor"
    arity = (1, 1)

    def run(self, ctx: Context, args: Args) -> Args | None:
        return None if args[0] in ctx.terms.functors else args


class CountLiteralValues(Builtin):
    """Bind the third argument to how many distinct literal values `(s p ?)` has (xsd:int).

    Not monotonic: the count changes as triples come, so a rule using it fires as a
    production rule, once per new match.
    """

    name = "countLiteralValues"
    arity = (3, 3)
    monotonic = False

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({2})

    def run(self, ctx: Context, args: Args) -> Args | None:
        s, p, count = args
        values = {
            ctx.terms.keys[o]
            for _, _, o in ctx.store.match(s, p, None)
            if isinstance(ctx.terms.term(o), Literal)
        }
        found = ctx.terms.id(Literal(str(len(values)), datatype=XSD.int))
        if count is None:
            return (s, p, found)
        return args if ctx.terms.same_value(count, found) else None


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
    IsFunctor(),
    NotFunctor(),
    CountLiteralValues(),
    Bound(),
    Unbound(),
)
