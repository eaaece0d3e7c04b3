"""Compute with numbers: `sum difference product quotient min max addOne`.

Each binds its last argument to the result, or checks it when already bound.
Integers stay integers, as in Jena: `quotient` of two integers truncates toward
zero (`quotient(7, 2)` is 3, `quotient(-7, 2)` is -3); anything else is computed
as a float. Results are typed as Jena types them: an xsd:int (an xsd:long past
2^31-1) or an xsd:double.
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from decimal import Decimal
from typing import ClassVar

from rdflib import XSD, Literal

from space.reasoning.builtins.base import Args, Builtin, Context

Number = int | float


def _number(ctx: Context, i: int | None) -> Number | None:
    value = ctx.terms.keys[i] if i is not None else None
    if isinstance(value, bool) or not isinstance(value, int | float | Decimal):
        return None
    return value if isinstance(value, int) else float(value)


def _bind(ctx: Context, args: Args, result: Number) -> Args | None:
    """Bind the last argument to `result`, or check it when it is already bound."""
    out = args[-1]
    if out is None:
        return (*args[:-1], ctx.terms.id(_literal(result)))
    value = _number(ctx, out)
    return args if value is not None and value == result else None


def _literal(result: Number) -> Literal:
    """Type a result as Jena does: an integer is an xsd:int (xsd:long past 2^31-1)."""
    if isinstance(result, int):
        return Literal(str(result), datatype=XSD.int if result < 2**31 else XSD.long)
    return Literal(result)


class _Binary(Builtin):
    """Bind the third argument to a function of the first two."""

    arity = (3, 3)
    function: ClassVar[Callable[[Number, Number], Number]]
    picks: ClassVar[bool] = False

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({2})

    def run(self, ctx: Context, args: Args) -> Args | None:
        a, b = _number(ctx, args[0]), _number(ctx, args[1])
        if a is None or b is None:
            return None
        result = type(self).function(a, b)
        if self.picks:  # min and max give one of their arguments, as it was written
            chosen = args[0] if result == a else args[1]
            if args[2] is None:
                return (args[0], args[1], chosen)
            return args if ctx.terms.same_value(args[2], chosen) else None  # type: ignore[arg-type]
        return _bind(ctx, args, result)


class Sum(_Binary):
    """Bind the third argument to the sum of the first two."""

    name = "sum"
    function = operator.add


class Difference(_Binary):
    """Bind the third argument to the first minus the second."""

    name = "difference"
    function = operator.sub


class Product(_Binary):
    """Bind the third argument to the product of the first two."""

    name = "product"
    function = operator.mul


class Min(_Binary):
    """Bind the third argument to the smaller of the first two."""

    name = "min"
    function = min
    picks = True


class Max(_Binary):
    """Bind the third argument to the larger of the first two."""

    name = "max"
    function = max
    picks = True


def _divide(a: Number, b: Number) -> Number:
    """Divide as Jena does: two integers give an integer truncated toward zero."""
    if isinstance(a, int) and isinstance(b, int):
        whole = abs(a) // abs(b)
        return whole if (a < 0) == (b < 0) else -whole
    return a / b


class Quotient(Builtin):
    """Bind the third argument to the first divided by the second (never by zero)."""

    name = "quotient"
    arity = (3, 3)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({2})

    def run(self, ctx: Context, args: Args) -> Args | None:
        a, b = _number(ctx, args[0]), _number(ctx, args[1])
        if a is None or not b:
            return None
        return _bind(ctx, args, _divide(a, b))


class AddOne(Builtin):
    """Bind the second argument to the first plus one."""

    name = "addOne"
    arity = (2, 2)

    def outputs(self, nargs: int) -> frozenset[int]:
        return frozenset({1})

    def run(self, ctx: Context, args: Args) -> Args | None:
        a = _number(ctx, args[0])
        return None if a is None else _bind(ctx, args, a + 1)


BUILTINS: tuple[Builtin, ...] = (
    Sum(),
    Difference(),
    Product(),
    Quotient(),
    Min(),
    Max(),
    AddOne(),
)
