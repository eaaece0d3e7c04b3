"""Errors of the rule engine, each named for what went wrong."""

from __future__ import annotations

from typing import TYPE_CHECKING

from space.errors import SpaceError, clause

if TYPE_CHECKING:
    from space.reasoning.delta import Delta


class RuleError(SpaceError):
    """A rule is well formed but cannot be used (unknown builtin, arity, unbound head variable).

    The message starts with `file:line:column:` and names the rule when it has a name.
    """


class RuleSyntaxError(RuleError):
    """A rules file does not follow the Jena rule syntax."""


class RuleLoopError(RuleError):
    """Production rules kept firing past the engine's limit; their firings were undone.

    Attributes:
        rules: the names of the rules that fired most in the runaway cycle, most first.
        kept: what the update changed without the production rules (a `Delta`), set by
            `RuleEngine.apply`: the caller's triples and their monotonic conclusions.
    """

    def __init__(self, message: str, rules: tuple[str, ...]) -> None:
        super().__init__(message)
        self.rules = rules
        self.kept: Delta | None = None


def unreadable(path: object, exc: OSError) -> str:
    """Return `path: why` for a file that cannot be opened, with the path as the user gave it."""
    if isinstance(exc, FileNotFoundError):
        return f"{path}: no such file"
    reason = exc.strerror or type(exc).__name__
    return f"{path}: {clause(reason)}"
