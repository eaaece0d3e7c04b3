"""Parse Jena rules files into `Rule`s as Jena 4.5's `Rule.Parser` reads them, errors located.

The grammar is Jena's (read from its source, not guessed): a rule is
`[name: body -> head]` or, unbracketed, `name: body -> head .` (the name is
optional, `<-` writes a backward rule head first, an empty body is an axiom);
a clause is a triple `(s p o)`, a builtin `name(args)` or a nested rule `[...]`;
a node is `?var`, `<iri>`, `prefix:local`, a quoted string with an optional
`^^datatype`, a number (`42` is an xsd:int, `4.2` an xsd:float, as Jena types
them), `_label` (a blank node), `name(args)` (a functor) or any other word (an
IRI, as Jena takes `foo` or `http://x#y`). `@prefix` lines apply to the whole
file; Jena's own prefixes (rdf, rdfs, owl, xsd, rb, jr, eg, drdfs) are known.
Included files come first, as in Jena. Beyond Jena: `'x'@en` written without a
gap is a language-tagged string, and an included file also sees the includer's
prefixes and is found relative to it; and after an error the reader skips to the end
of the broken rule and reads on, so that every error of every file is found in one run.
This module reads files; `grammar` reads one rule from their tokens.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

from space.reasoning.builtins import Registry
from space.reasoning.checks import check_rule, located, mark_shared_names
from space.reasoning.directives import ignored_text, prefix_line, uri_argument
from space.reasoning.errors import RuleError, RuleSyntaxError, unreadable
from space.reasoning.forms import blank_head_variables, flatten, regex_groups
from space.reasoning.grammar import AT_END, RuleParser
from space.reasoning.listmaps import expand_list_maps
from space.reasoning.rules import Location, Rule
from space.reasoning.rulesets import is_builtin_ruleset, read_builtin_ruleset
from space.reasoning.tokens import Directive, lex

RDF_NS = "http://www.w3.org/1999/02/22-rdf-syntax-ns#"
RDFS_NS = "http://www.w3.org/2000/01/rdf-schema#"
DEFAULT_PREFIXES = {
    "rdf": RDF_NS,
    "rdfs": RDFS_NS,
    "drdfs": "urn:x-hp-direct-predicate:http_//www.w3.org/2000/01/rdf-schema#",
    "owl": "http://www.w3.org/2002/07/owl#",
    "jr": "http://jena.hpl.hp.com/2003/JenaReasoner#",
    "rb": "urn:x-hp-jena:rubrik/",
    "eg": "urn:x-hp:eg/",
    "xsd": "http://www.w3.org/2001/XMLSchema#",
}
log = logging.getLogger(__name__)


def parse_rules(
    text: str,
    registry: Registry,
    *,
    source: str = "<string>",
    prefixes: dict[str, str] | None = None,
    warn: Callable[[str], None] | None = None,
) -> list[Rule]:
    """Parse the text of a rules file; `@include` paths resolve against `source`'s folder.

    A rule name used twice is accepted, as Jena does, with a warning naming both places
    (given to `warn`, by default logged).

    Raises:
        RuleSyntaxError: the text is not valid Jena rule syntax, or an include is missing.
        RuleError: a rule uses an unknown builtin, a wrong arity, a bad drop/remove index
            or a builtin input nothing binds.
    """
    warn = warn or log.warning
    reader = _Reader(registry, (), warn, [])
    rules = list(reader.read(text, source, dict(prefixes or DEFAULT_PREFIXES)))
    if reader.errors:
        raise _first(reader.errors)
    return mark_shared_names(rules, warn)


def load_rules(
    paths: Iterable[str | Path],
    registry: Registry,
    warn: Callable[[str], None] | None = None,
) -> list[Rule]:
    """Parse rules files in order, each file's includes first; warnings as `parse_rules`.

    Raises:
        RuleSyntaxError, RuleError: as `parse_rules`; a missing file is a RuleSyntaxError.
            The message is the first error's, saying how many more there are.
    """
    rules, errors = check_rules(paths, registry, warn)
    if errors:
        raise _first(errors)
    return rules


def check_rules(
    paths: Iterable[str | Path],
    registry: Registry,
    warn: Callable[[str], None] | None = None,
) -> tuple[list[Rule], list[RuleError]]:
    """Parse rules files as `load_rules` does, but return every error instead of raising.

    After an error the reader skips to the end of the broken rule and reads on, so the
    errors are all those of all files (in reading order, each once); the rules are those
    that are well formed.
    """
    warn = warn or log.warning
    reader = _Reader(registry, (), warn, [])
    rules: list[Rule] = []
    for path in paths:
        try:
            rules.extend(reader.read_file(Path(path), DEFAULT_PREFIXES))
        except RuleError as exc:
            reader.record(exc)
    return mark_shared_names(rules, warn), reader.errors


def _first(errors: list[RuleError]) -> RuleError:
    """Return the first error, its message saying how many more were found."""
    first = errors[0]
    if len(errors) == 1:
        return first
    more = len(errors) - 1
    note = f" (and {more} more error{'s' if more > 1 else ''}: `tspace rules check` lists them)"
    return type(first)(f"{first}{note}")


class _Reader:
    """Turn files into rules, following includes (and refusing include cycles).

    Errors are not raised but recorded in `errors` (shared with the readers of included
    files), the reader skipping what it cannot read.
    """

    def __init__(
        self,
        registry: Registry,
        including: tuple[Path, ...],
        warn: Callable[[str], None],
        errors: list[RuleError],
    ) -> None:
        self.registry = registry
        self.including = including
        self.warn = warn
        self.errors = errors

    def record(self, error: RuleError) -> None:
        """Keep `error` unless the same one is already kept (a rule read twice on recovery)."""
        if all(str(error) != str(kept) for kept in self.errors):
            self.errors.append(error)

    def read_file(
        self, path: Path, prefixes: dict[str, str], where: Location | None = None
    ) -> Iterator[Rule]:
        resolved = path.resolve()
        if resolved in self.including:
            raise RuleSyntaxError(located(where, None, f"include cycle through {path}"))
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            message = unreadable(path, exc)
            raise RuleSyntaxError(
                located(where, None, f"cannot include {message}" if where else message)
            ) from exc
        except UnicodeDecodeError as exc:
            raise RuleSyntaxError(located(where, None, f"{path}: not UTF-8 text")) from exc
        inner = _Reader(self.registry, (*self.including, resolved), self.warn, self.errors)
        yield from inner.read(text, str(path), dict(prefixes))

    def read(self, text: str, source: str, prefixes: dict[str, str]) -> Iterator[Rule]:
        lexed = lex(text, source)
        includes = []
        for directive in lexed.directives:
            ignored = ignored_text(directive.rest)
            if ignored:
                self.warn(
                    f"{directive.where}: text after {directive.keyword}'s <...> is ignored, as "
                    f"Jena ignores it: {ignored[:40]!r} (write it on a line of its own)"
                )
            if directive.keyword == "@prefix":
                try:
                    name, iri = prefix_line(directive)
                except RuleError as exc:
                    self.record(exc)
                    continue
                prefixes[name] = iri
            else:
                includes.append(directive)
        for directive in includes:
            try:
                yield from self.include(directive, source, prefixes)
            except RuleError as exc:
                self.record(exc)
        parser = RuleParser(lexed.tokens, lexed.end, self.registry, prefixes)
        while not parser.done():
            start = parser.position
            try:
                rules = self.complete(parser.rule())
            except RuleError as exc:
                self.record(exc)
                resume = parser.resume(start)
                if resume.unclosed and AT_END not in str(exc):
                    opening, label = lexed.tokens[start : start + 2]
                    name = label.text[:-1] if label.text.endswith(":") else None
                    message = "syntax error: this '[' is never closed (a ']' is missing)"
                    self.record(RuleSyntaxError(located(opening.where, name, message)))
                continue
            yield from rules

    def complete(self, rule: Rule) -> list[Rule]:
        """Return the rules one parsed rule stands for (nested, list maps), each checked."""
        done = []
        for nested in flatten(rule):
            for expanded in expand_list_maps(nested, self.registry):
                expanded = blank_head_variables(regex_groups(expanded), self.registry)
                check_rule(expanded)
                done.append(expanded)
        return done

    def include(
        self, directive: Directive, source: str, prefixes: dict[str, str]
    ) -> Iterator[Rule]:
        target = uri_argument(directive.rest, directive)
        if is_builtin_ruleset(target):
            text, name = read_builtin_ruleset(target, directive.where)
            yield from self.read(text, name, dict(DEFAULT_PREFIXES))
            return
        if target.startswith("file:"):
            target = target[5:].removeprefix("//")
        path = Path(target)
        if not path.is_absolute():
            path = Path(source).parent / path
        yield from self.read_file(path, prefixes, directive.where)
