"""Find where to read on after an error in a rule, so one run reports every broken rule.

A bracketed rule ends at the `]` that closes its `[`; an unbracketed one at the next `.`
outside brackets. When a `[` is never closed, the rule would swallow the rest of the file,
so reading goes on at the next `[` that opens a line: rules are written one after another,
each starting a line, and what is inside a rule that is cut off cannot be trusted anyway.
"""

from __future__ import annotations

from dataclasses import dataclass

from space.reasoning.tokens import Kind, Token


@dataclass(frozen=True)
class Resume:
    """Where to read on (a token index); `unclosed`: at a later rule, the `[` never closed."""

    at: int
    unclosed: bool


def resume_after(tokens: list[Token], start: int) -> Resume:
    """Return where the rule that begins at `tokens[start]` ends, to read on after an error in it.

    The returned index is always past `start`, so a reader that resumes there makes progress.
    """
    bracketed = _is(tokens[start], "[")
    depth = 0
    for i in range(start, len(tokens)):
        token = tokens[i]
        if _is(token, "["):
            depth += 1
        elif _is(token, "]"):
            depth -= 1
            if bracketed and depth == 0:
                return Resume(i + 1, unclosed=False)
        elif not bracketed and depth <= 0 and token.kind is Kind.WORD and token.text == ".":
            return Resume(i + 1, unclosed=False)
    for i in range(start + 1, len(tokens)):
        if _is(tokens[i], "[") and tokens[i].where.line > tokens[i - 1].where.line:
            return Resume(i, unclosed=bracketed)
    return Resume(len(tokens), unclosed=False)


def _is(token: Token, text: str) -> bool:
    return token.kind is Kind.SYNTAX and token.text == text
