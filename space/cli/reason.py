"""`tspace reason`: run rules over a Turtle file, apply an update, print the state."""

from __future__ import annotations

import argparse
import sys

ORDER = 70


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `reason` sub-command."""
    p = sub.add_parser(
        "reason",
        help="run rules over RDF files and print the resulting state",
        description="Load the ontology and the data, run the rules to a fixpoint, apply the "
        "update, and print the state as Turtle. As in the space, a value of an "
        "owl:FunctionalProperty in the update replaces the asserted old value. "
        "The production rules that fired, and what print() prints, go to stderr. "
        "OWL RL runs with the rules only when an --ontology is given (and not --no-owl); "
        "otherwise only the rules run, as Jena's GenericRuleReasoner runs them (backward "
        "rules and rules nested in heads over the forward rules' closure, as its hybrid mode). "
        "The OWL 2 RL conflicts (triples that cannot all hold) are listed on stderr.",
    )
    p.add_argument("--rules", nargs="+", required=True, metavar="RULES", help="rules files")
    p.add_argument("--data", nargs="+", required=True, metavar="DATA", help="RDF data files")
    p.add_argument("--update", nargs="*", default=[], metavar="FILE", help="triples to assert")
    p.add_argument("--retract", nargs="*", default=[], metavar="FILE", help="triples to retract")
    p.add_argument("--ontology", nargs="*", default=[], metavar="FILE", help="OWL ontology files")
    p.add_argument(
        "--no-owl",
        action="store_true",
        help="no OWL RL even with --ontology (the ontology is still loaded as data)",
    )
    p.add_argument(
        "--show",
        choices=("all", "asserted", "inferred"),
        default="all",
        help="which triples to print (default all)",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Reason and print the state on stdout (Turtle) and the firings on stderr."""
    from rdflib import OWL, RDF, Graph, Literal, URIRef

    from space.functional import replace_functional
    from space.reasoning import Origin, read_graph
    from space.reasoning.hybrid import engine_from_files

    ontology = read_graph(args.ontology)

    def to_stderr(text: str) -> None:
        print(text, file=sys.stderr)

    engine = engine_from_files(
        rules=args.rules,
        ontology=args.ontology,
        owl=bool(args.ontology) and not args.no_owl,
        printer=to_stderr,
    )
    deltas = [engine.load(read_graph(args.data))]
    update, retract = read_graph(args.update), read_graph(args.retract)
    if len(update) or len(retract):
        functional = set(ontology.subjects(RDF.type, OWL.FunctionalProperty))
        change = replace_functional(
            update, functional.__contains__, lambda s, p: engine.graph.objects(s, p)
        )
        deltas.append(engine.apply(added=change.kept, removed=[*retract, *change.replaced]))
    for delta in deltas:
        for firing in delta.firings:
            print(
                f"# fired {firing.rule}: retracted {len(firing.retracted)}, "
                f"asserted {len(firing.asserted)}",
                file=sys.stderr,
            )
    for conflict in engine.conflicts():
        print(f"# conflict {conflict}", file=sys.stderr)
    origin = {"all": None, "asserted": Origin.ASSERTED, "inferred": Origin.INFERRED}[args.show]
    out = Graph()
    for prefix, namespace in (*ontology.namespaces(), *read_graph(args.data).namespaces()):
        out.bind(prefix, namespace, override=False)
    skipped = 0
    for triple in engine.triples(origin):
        if isinstance(triple[0], Literal) or not isinstance(triple[1], URIRef):
            skipped += 1  # a rule put a literal where RDF allows none: not Turtle
            continue
        out.add(triple)
    if skipped:
        print(
            f"# {skipped} derived triple{'s' if skipped > 1 else ''} with a literal subject "
            "or predicate not printed (not RDF)",
            file=sys.stderr,
        )
    sys.stdout.write(out.serialize(format="turtle"))
    return 0
