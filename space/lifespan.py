"""Read and check a write's lifespan: how long its triples live unless written again.

One rule everywhere (Python API, command line, launch files, the store's
intake): a lifespan is a positive, finite number of seconds, at most
`MAX_LIFESPAN`; 0 or None means permanent. Text may carry a unit: `500ms`,
`5s`, `2m`, `1h` (plain numbers are seconds).
"""

from __future__ import annotations

import math
import re

from space.errors import InputError

MAX_LIFESPAN = 10 * 365 * 24 * 3600.0  # seconds; beyond this, write it permanent
EXPIRY_AGENT = "tspace-store"  # the agent of the changesets that retract expired writes
_UNITS = {"ms": 0.001, "s": 1.0, "m": 60.0, "h": 3600.0, "": 1.0}
_TEXT = re.compile(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(ms|s|m|h|)\s*")


def check_lifespan(value: object) -> float | None:
    """Return a lifespan in seconds (None for permanent) from a number or a text like `5s`.

    Raises:
        InputError: not a number of seconds in (0, MAX_LIFESPAN], nor a text with a unit.
    """
    if value is None or value == 0 or value == "0":
        return None
    if isinstance(value, str):
        found = _TEXT.fullmatch(value)
        if not found:
            raise InputError(
                f"a lifespan is a number with a unit (500ms, 5s, 2m, 1h), got {value!r}"
            )
        return check_lifespan(float(found[1]) * _UNITS[found[2]])
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"a lifespan is a number of seconds, got {type(value).__name__}")
    seconds = float(value)
    if not math.isfinite(seconds) or not 0 < seconds <= MAX_LIFESPAN:
        raise InputError(
            f"a lifespan is a positive number of seconds up to {MAX_LIFESPAN:g} "
            f"(0 or none: permanent), got {value!r}"
        )
    return seconds
