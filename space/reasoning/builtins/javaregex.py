"""Translate a Java regex (what Jena's `regex` builtin takes) into Python's `re` syntax.

Most Java syntax is Python's too. What differs is rewritten: POSIX and Unicode
classes (`\\p{Alpha}`, `\\P{Digit}`, `\\p{L}`), `\\Q...\\E` quoting, `\\z`, `\\Z`, `\\h`,
named groups `(?<name>...)`. What Python cannot express is refused with the reason,
when the rule is read: never a pattern that silently matches nothing.
"""

from __future__ import annotations

import re

_CLASSES = {
    "Lower": "a-z",
    "Upper": "A-Z",
    "ASCII": "\\x00-\\x7F",
    "Alpha": "A-Za-z",
    "Digit": "0-9",
    "Alnum": "A-Za-z0-9",
    "Punct": "!-/:-@\\[-`{-~",
    "Graph": "!-~",
    "Print": " -~",
    "Blank": " \\t",
    "Cntrl": "\\x00-\\x1F\\x7F",
    "XDigit": "0-9a-fA-F",
    "Space": " \\t\\n\\x0B\\f\\r",
    "javaLowerCase": "a-z",
    "javaUpperCase": "A-Z",
    "javaWhitespace": "\\s",
    "L": "^\\W\\d_",
    "IsAlphabetic": "^\\W\\d_",
    "IsLetter": "^\\W\\d_",
    "N": "\\d",
    "Nd": "\\d",
    "IsDigit": "\\d",
}
_TOKEN = re.compile(
    r"\\Q(.*?)(?:\\E|$)|\\([pP])\{(\w+)\}|\\([pP])(\w)|\\[zZh]|\(\?<(\w+)>|\\.", re.S
)


class JavaRegexError(ValueError):
    """A Java regex this engine cannot run the same way."""


def translate(pattern: str) -> re.Pattern[str]:
    """Return the compiled Python equivalent of a Java regex.

    Raises:
        JavaRegexError: the pattern uses Java syntax with no Python equivalent, or is invalid.
    """
    out: list[str] = []
    position = 0
    in_class = False
    for match in _TOKEN.finditer(pattern):
        out.append(pattern[position : match.start()])
        in_class = _class_state(pattern[position : match.start()], in_class)
        out.append(_rewrite(match, in_class))
        position = match.end()
    out.append(pattern[position:])
    try:
        return re.compile("".join(out))
    except re.error as exc:
        raise JavaRegexError(f"regex {pattern!r}: {exc}") from None


def _class_state(text: str, in_class: bool) -> bool:
    for char in text:
        if char == "[":
            in_class = True
        elif char == "]":
            in_class = False
    return in_class


def _rewrite(match: re.Match[str], in_class: bool) -> str:
    text = match.group(0)
    if text.startswith("\\Q"):
        return re.escape(match.group(1))
    if match.group(2) or match.group(4):
        negated = (match.group(2) or match.group(4)) == "P"
        name = match.group(3) or match.group(5)
        name = name[2:] if name.startswith("Is") and name[2:] in _CLASSES else name
        members = _CLASSES.get(name)
        if members is None:
            raise JavaRegexError(f"the Java regex class \\p{{{name}}} is not supported")
        if members.startswith("^"):  # already a negated set: \p{L} is [^\W\d_]
            if in_class:
                raise JavaRegexError(f"\\p{{{name}}} inside [...] is not supported")
            return f"[{members}]" if not negated else "[\\W\\d_]"
        if in_class:
            if negated:
                raise JavaRegexError(f"\\P{{{name}}} inside [...] is not supported")
            return members
        return f"[{'^' if negated else ''}{members}]"
    if text == "\\z":
        return "\\Z"
    if text == "\\Z":
        return "(?=\\n?\\Z)"
    if text == "\\h":
        return "[ \\t\\xA0\\u1680\\u180e\\u2000-\\u200a\\u202f\\u205f\\u3000]"
    if match.group(6):
        return f"(?P<{match.group(6)}>"
    return text
