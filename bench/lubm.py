"""Generate a LUBM-like university data set: an OWL 2 RL ontology (Turtle) and N-Triples data.

The shape follows LUBM's univ-bench (universities, departments, faculty,
students, courses, publications; a class and property hierarchy, inverse and
transitive properties, domains and ranges, and Chair/Student/Employee defined
by someValuesFrom and intersections), scaled by the number of departments.
One department is about 3,300 triples; 30 make ~100k, 300 ~1M. Seeded:
the same arguments give the same files.

    python bench/lubm.py --departments 30 --out /tmp/lubm100k
"""

from __future__ import annotations

import argparse
import random
from pathlib import Path

U = "http://example.org/univ-bench#"
ONTOLOGY = f"""@prefix rdf: <http://www.w3.org/1999/02/22-rdf-syntax-ns#> .
@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .
@prefix owl: <http://www.w3.org/2002/07/owl#> .
@prefix ub: <{U}> .

<{U[:-1]}> a owl:Ontology .
ub:Organization a owl:Class .
ub:University a owl:Class ; rdfs:subClassOf ub:Organization .
ub:Department a owl:Class ; rdfs:subClassOf ub:Organization .
ub:ResearchGroup a owl:Class ; rdfs:subClassOf ub:Organization .
ub:Person a owl:Class .
ub:Employee a owl:Class ; owl:intersectionOf ( ub:Person
    [ a owl:Restriction ; owl:onProperty ub:worksFor ; owl:someValuesFrom ub:Organization ] ) .
ub:Faculty a owl:Class ; rdfs:subClassOf ub:Employee .
ub:Professor a owl:Class ; rdfs:subClassOf ub:Faculty .
ub:FullProfessor a owl:Class ; rdfs:subClassOf ub:Professor .
ub:AssociateProfessor a owl:Class ; rdfs:subClassOf ub:Professor .
ub:AssistantProfessor a owl:Class ; rdfs:subClassOf ub:Professor .
ub:Lecturer a owl:Class ; rdfs:subClassOf ub:Faculty .
ub:Chair a owl:Class ; owl:intersectionOf ( ub:Person
    [ a owl:Restriction ; owl:onProperty ub:headOf ; owl:someValuesFrom ub:Department ] ) .
ub:Student a owl:Class ; owl:intersectionOf ( ub:Person
    [ a owl:Restriction ; owl:onProperty ub:takesCourse ; owl:someValuesFrom ub:Course ] ) .
ub:UndergraduateStudent a owl:Class ; rdfs:subClassOf ub:Student .
ub:GraduateStudent a owl:Class ; rdfs:subClassOf ub:Person .
ub:TeachingAssistant a owl:Class ; rdfs:subClassOf ub:Person .
ub:ResearchAssistant a owl:Class ; rdfs:subClassOf ub:Person .
ub:Work a owl:Class .
ub:Course a owl:Class ; rdfs:subClassOf ub:Work .
ub:GraduateCourse a owl:Class ; rdfs:subClassOf ub:Course .
ub:Publication a owl:Class .
ub:memberOf a owl:ObjectProperty ; rdfs:domain ub:Person ; rdfs:range ub:Organization .
ub:member a owl:ObjectProperty ; owl:inverseOf ub:memberOf .
ub:worksFor a owl:ObjectProperty ; rdfs:subPropertyOf ub:memberOf .
ub:headOf a owl:ObjectProperty ; rdfs:subPropertyOf ub:worksFor .
ub:subOrganizationOf a owl:ObjectProperty , owl:TransitiveProperty ;
    rdfs:domain ub:Organization ; rdfs:range ub:Organization .
ub:takesCourse a owl:ObjectProperty ; rdfs:range ub:Course .
ub:teacherOf a owl:ObjectProperty ; rdfs:domain ub:Faculty ; rdfs:range ub:Course .
ub:advisor a owl:ObjectProperty ; rdfs:domain ub:Person ; rdfs:range ub:Professor .
ub:publicationAuthor a owl:ObjectProperty ; rdfs:domain ub:Publication ; rdfs:range ub:Person .
ub:degreeFrom a owl:ObjectProperty ; rdfs:domain ub:Person ; rdfs:range ub:University .
ub:hasAlumnus a owl:ObjectProperty ; owl:inverseOf ub:degreeFrom .
ub:undergraduateDegreeFrom a owl:ObjectProperty ; rdfs:subPropertyOf ub:degreeFrom .
ub:doctoralDegreeFrom a owl:ObjectProperty ; rdfs:subPropertyOf ub:degreeFrom .
ub:teachingAssistantOf a owl:ObjectProperty ; rdfs:domain ub:TeachingAssistant ;
    rdfs:range ub:Course .
ub:name a owl:DatatypeProperty .
ub:emailAddress a owl:DatatypeProperty .
"""


def _iri(*parts: object) -> str:
    return f"<http://example.org/u{parts[0]}/" + "/".join(str(p) for p in parts[1:]) + ">"


def generate(departments: int, seed: int = 0) -> list[str]:
    """Return the data's N-Triples lines for `departments` departments (15 per university)."""
    rnd = random.Random(seed)
    out: list[str] = []
    universities = max(1, (departments + 14) // 15)
    t = f"<{U}"

    def add(s: str, p: str, o: str) -> None:
        out.append(f"{s} {t}{p}> {o} .")

    def a(s: str, c: str) -> None:
        out.append(f"{s} <http://www.w3.org/1999/02/22-rdf-syntax-ns#type> {t}{c}> .")

    def text(value: str) -> str:
        return f'"{value}"'

    unis = [_iri(u, "") for u in range(universities)]
    for uni in unis:
        a(uni, "University")
    for d in range(departments):
        u = d // 15
        dept = _iri(u, f"dept{d}")
        a(dept, "Department")
        add(dept, "subOrganizationOf", unis[u])
        add(dept, "name", text(f"Department {d}"))
        groups = [_iri(u, f"dept{d}", f"group{g}") for g in range(10)]
        for g in groups:
            a(g, "ResearchGroup")
            add(g, "subOrganizationOf", dept)
        courses = [_iri(u, f"dept{d}", f"course{c}") for c in range(40)]
        grad_courses = [_iri(u, f"dept{d}", f"gcourse{c}") for c in range(20)]
        for c in courses:
            a(c, "Course")
        for c in grad_courses:
            a(c, "GraduateCourse")
        faculty = []
        kinds = [("FullProfessor", 7), ("AssociateProfessor", 10), ("AssistantProfessor", 8)]
        kinds.append(("Lecturer", 5))
        for kind, n in kinds:
            for i in range(n):
                f = _iri(u, f"dept{d}", f"{kind}{i}")
                faculty.append(f)
                a(f, kind)
                add(f, "worksFor", dept)
                add(f, "name", text(f"{kind} {i}"))
                add(f, "emailAddress", text(f"{kind}{i}@dept{d}.u{u}.edu"))
                add(f, "teacherOf", rnd.choice(courses))
                add(f, "teacherOf", rnd.choice(grad_courses))
                add(f, "undergraduateDegreeFrom", rnd.choice(unis))
                add(f, "doctoralDegreeFrom", rnd.choice(unis))
                for k in range(5):
                    pub = _iri(u, f"dept{d}", f"{kind}{i}", f"pub{k}")
                    a(pub, "Publication")
                    add(pub, "publicationAuthor", f)
        add(faculty[0], "headOf", dept)
        professors = faculty[:25]
        for i in range(200):
            s = _iri(u, f"dept{d}", f"ug{i}")
            a(s, "UndergraduateStudent")
            add(s, "memberOf", dept)
            add(s, "name", text(f"Undergraduate {i}"))
            for c in rnd.sample(courses, 3):
                add(s, "takesCourse", c)
            if i % 5 == 0:
                add(s, "advisor", rnd.choice(professors))
        for i in range(60):
            s = _iri(u, f"dept{d}", f"grad{i}")
            a(s, "GraduateStudent")
            add(s, "memberOf", dept)
            add(s, "name", text(f"Graduate {i}"))
            add(s, "undergraduateDegreeFrom", rnd.choice(unis))
            add(s, "advisor", rnd.choice(professors))
            for c in rnd.sample(grad_courses, 2):
                add(s, "takesCourse", c)
            if i % 4 == 0:
                a(s, "TeachingAssistant")
                add(s, "teachingAssistantOf", rnd.choice(courses))
            if i % 3 == 0:
                a(s, "ResearchAssistant")
                add(s, "worksFor", rnd.choice(groups))
    return out


def write(departments: int, out: Path, seed: int = 0) -> tuple[Path, Path]:
    """Write `ontology.ttl` and `data.nt` into `out`; return their paths."""
    out.mkdir(parents=True, exist_ok=True)
    ontology, data = out / "ontology.ttl", out / "data.nt"
    ontology.write_text(ONTOLOGY)
    data.write_text("\n".join(generate(departments, seed)) + "\n")
    return ontology, data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--departments", type=int, default=30)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    ontology, data = write(args.departments, args.out, args.seed)
    lines = sum(1 for _ in data.open())
    print(f"{ontology}\n{data}: {lines} triples")


if __name__ == "__main__":
    main()
