"""Compile the OWL 2 RL/RDF rules an ontology needs into ordinary rules (named as in the spec).

Each axiom of the ontology becomes instance rules whose body starts with the
axiom triple itself, e.g. `cax-sco` for `ac:Speaker rdfs:subClassOf
ac:InteractionDevice` is `[(ac:Speaker rdfs:subClassOf ac:InteractionDevice),
(?x rdf:type ac:Speaker) -> (?x rdf:type ac:InteractionDevice)]`. So a rule is
indexed by its constant predicate and object, `why` names the axiom, and
retracting the axiom retracts what it entailed. Rules whose head is `false`
(cax-dw, prp-irp, ...) derive a conflict (`space.reasoning.conflicts`).
Axioms added after the engine was built are closed over at schema level
(`scm-*`) but compile no new instance rules: build a new engine for a new
ontology. The rules, table by table, are in `owl_classes`, `owl_properties`
and `owl_schema`; constructs outside OWL 2 RL are named in a warning
(`owl_profile`).
"""

from __future__ import annotations

from rdflib import Graph

from space.reasoning.owl_classes import class_axioms, class_expressions
from space.reasoning.owl_profile import warn_outside_rl
from space.reasoning.owl_properties import property_axioms
from space.reasoning.owl_schema import axiomatic, equality, schema
from space.reasoning.rules import Rule


def owl_rules(tbox: Graph) -> list[Rule]:
    """Return the OWL 2 RL rules for the axioms of `tbox`, plus equality and schema rules.

    Warns (`UnsupportedAxiom`) about each construct of `tbox` outside OWL 2 RL.
    """
    warn_outside_rl(tbox)
    return [
        *class_axioms(tbox),
        *property_axioms(tbox),
        *class_expressions(tbox),
        *equality(tbox),
        *schema(tbox),
        *axiomatic(),
    ]
