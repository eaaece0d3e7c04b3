"""Order dates and date-times as XSD does (and Jena with it), timezones or not.

A date is the date-time at its midnight. Two values both with or both without a
timezone compare directly. One without a timezone stands for any instant within
14 hours of it, so against one with a timezone it is before (or after) only when
all of those instants are: otherwise the two are not ordered (every test fails).
"""

from __future__ import annotations

from datetime import UTC, date, datetime, timedelta

_SPREAD = timedelta(hours=14)


def as_datetime(value: date | datetime) -> datetime:
    """Return a date-time; a date becomes its midnight (with the date's timezone, if any)."""
    if isinstance(value, datetime):
        return value
    return datetime(value.year, value.month, value.day)


def compare(a: date | datetime, b: date | datetime) -> int | None:
    """Return -1, 0 or 1 as `a` is before, at or after `b`; None when XSD leaves them unordered."""
    x, y = as_datetime(a), as_datetime(b)
    if (x.tzinfo is None) == (y.tzinfo is None):
        return (x > y) - (x < y)
    if x.tzinfo is None:
        flipped = compare(y, x)
        return None if flipped is None else -flipped
    earliest = y.replace(tzinfo=UTC) - _SPREAD
    latest = y.replace(tzinfo=UTC) + _SPREAD
    if x < earliest:
        return -1
    if x > latest:
        return 1
    return None
