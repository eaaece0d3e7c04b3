"""Type the numbers written in rules as Jena does: `42` is an xsd:int, `4.2` an xsd:float.

A number Jena cannot type that way (`3000000000`, `1e5`) is a plain string, as in Jena.
"""

from __future__ import annotations

import re

from rdflib import XSD, Literal

_INT = re.compile(r"[+-]?\d+")
_FLOAT = re.compile(r"[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?")
_INT_RANGE = range(-(2**31), 2**31)


def number(text: str) -> Literal:
    """Return the literal Jena's rule parser makes of a word that starts like a number."""
    if "." in text:
        if _FLOAT.fullmatch(text):
            return Literal(text, datatype=XSD.float)
    elif _INT.fullmatch(text) and int(text) in _INT_RANGE:
        return Literal(text, datatype=XSD.int)
    return Literal(text)
