"""The reasoning engine: Jena rules and OWL RL, kept up to date incrementally."""

from space.reasoning.builtins import Builtin, Registry, default_registry
from space.reasoning.bulk import read_triples
from space.reasoning.conflicts import Conflict
from space.reasoning.delta import Delta, Firing, Origin, TripleChange, Why
from space.reasoning.engine import RuleEngine
from space.reasoning.errors import RuleError, RuleLoopError, RuleSyntaxError
from space.reasoning.explain import Explainer
from space.reasoning.hybrid import Engine, HybridEngine, build_engine, engine_from_files
from space.reasoning.owl_profile import UnsupportedAxiom
from space.reasoning.parser import load_rules, parse_rules
from space.reasoning.rdffiles import read_graph
from space.reasoning.rules import Rule

__all__ = [
    "Builtin",
    "Conflict",
    "Delta",
    "Engine",
    "Explainer",
    "Firing",
    "HybridEngine",
    "Origin",
    "Registry",
    "Rule",
    "RuleEngine",
    "RuleError",
    "RuleLoopError",
    "RuleSyntaxError",
    "TripleChange",
    "UnsupportedAxiom",
    "Why",
    "build_engine",
    "default_registry",
    "engine_from_files",
    "load_rules",
    "parse_rules",
    "read_graph",
    "read_triples",
]
