"""Compare terms by value: `equal notEqual lessThan greaterThan le ge`."""

from __future__ import annotations

import operator
from collections.abc import Callable
from datetime import date, datetime, time
from decimal import Decimal
from typing import ClassVar

from space.reasoning.builtins import temporal
from space.reasoning.builtins.base import Args, Builtin, Context

_ORDERED = (int, float, Decimal, datetime, date, time)


class Equal(Builtin):
    """Accept when both arguments have the same value (`1` equals `1.0`)."""

    name = "equal"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        a, b = args
        return args if ctx.terms.same_value(a, b) else None  # type: ignore[arg-type]


class NotEqual(Builtin):
    """Accept when the arguments have different values."""

    name = "notEqual"
    arity = (2, 2)

    def run(self, ctx: Context, args: Args) -> Args | None:
        a, b = args
        return None if ctx.terms.same_value(a, b) else args  # type: ignore[arg-type]


class _Ordering(Builtin):
    """Accept when two numbers, or two dates or date-times, are in the given order.

    Dates and date-times are ordered as XSD orders them (`temporal`): a date is its
    midnight, and a value without a timezone is unordered against one with a timezone
    less than 14 hours away.
    """

    arity = (2, 2)
    compare: ClassVar[Callable[[object, object], bool]]

    def run(self, ctx: Context, args: Args) -> Args | None:
        a, b = (ctx.terms.keys[i] for i in args)  # type: ignore[index]
        if not (isinstance(a, _ORDERED) and isinstance(b, _ORDERED)) or isinstance(a, bool):
            return None
        if isinstance(a, date) and isinstance(b, date):  # datetime is a date too
            order = temporal.compare(a, b)
            return args if order is not None and type(self).compare(order, 0) else None
        try:
            return args if type(self).compare(a, b) else None
        except TypeError:  # a number against a time, or naive against aware times
            return None


class LessThan(_Ordering):
    """Accept when the first value is less than the second."""

    name = "lessThan"
    compare = operator.lt


class GreaterThan(_Ordering):
    """Accept when the first value is greater than the second."""

    name = "greaterThan"
    compare = operator.gt


class Le(_Ordering):
    """Accept when the first value is less than or equal to the second."""

    name = "le"
    compare = operator.le


class Ge(_Ordering):
    """Accept when the first value is greater than or equal to the second."""

    name = "ge"
    compare = operator.ge


BUILTINS: tuple[Builtin, ...] = (Equal(), NotEqual(), LessThan(), GreaterThan(), Le(), Ge())
