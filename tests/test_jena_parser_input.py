"""Any text given as a rules file is rules or one RuleError: never another exception."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from space.reasoning import RuleError, default_registry, parse_rules

REG = default_registry()
PIECES = [
    "[", "]", "(", ")", "->", "<-", ".", ",", " ", "\n", "?x", "?y", "ex:p", "<http://a>",
    "'s'", '"t"', "^^", "xsd:int", "42", "4.2", "-1", "r1:", "noValue", "sum", "drop",
    "remove", "print", "f", "@prefix ex: <http://e/>\n", "@include <nothing>\n", "#c\n",
    "// c\n", "_:b", "*", "'", "\\", "table", "hide", "regex", "'\\\\p{X}'", "@en",
    "listMapAsSubject", "http://x#y", "@prefix", "<", ">",
]  # fmt: skip


@settings(max_examples=400, deadline=None)
@given(st.lists(st.sampled_from(PIECES), min_size=1, max_size=30))
def test_any_token_soup_parses_or_raises_one_rule_error(pieces):
    try:
        rules = parse_rules("".join(pieces), REG, source="f.rules", warn=lambda m: None)
    except RuleError as exc:
        assert str(exc).startswith("f.rules:")  # says where
    else:
        assert isinstance(rules, list)
