"""Record Apache Jena 4.5's answers into tests/data/jena/, so CI checks tspace without Jena.

Needs Java, Jena 4.5's jars (Debian: libapache-jena-java, in /usr/share/java) and a
git clone of apache/jena (for its tests and test data, read at tag jena-4.5.0):

    python bench/jena_referee.py --jena-git ~/src/jena/.git

Writes:
- tests/data/jena/etc/*.rules: Jena's bundled rule sets (from jena-core.jar);
- tests/data/jena/data/*: Jena's test data the bundled rule sets run on;
- tests/data/jena/expected/<rules>@<data>.nt: Jena's closure (hybrid mode), or `error: ...`;
- tests/data/jena/rule_texts.json: every rule text in Jena's rule tests, whether Jena parses it;
- tests/data/jena/cases/*.rules + expected: hand-transcribed forward-rule test cases
  (tests/data/jena/cases/*.json), run through Jena.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import tempfile
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "tests" / "data" / "jena"
JAVA = Path("/usr/share/java")
REF = "jena-4.5.0"
TESTS = "jena-core/src/test/java/org/apache/jena/reasoner/rulesys"
TEST_CLASSES = (
    f"{TESTS}/test/TestBasics.java",
    f"{TESTS}/test/TestFBRules.java",
    f"{TESTS}/test/TestGenericRules.java",
    f"{TESTS}/test/TestRETE.java",
    f"{TESTS}/test/TestComparatorBuiltins.java",
    f"{TESTS}/test/TestBasicLP.java",
    f"{TESTS}/test/TestBugs.java",
    f"{TESTS}/TestRuleUtil.java",
)
DATA = {
    "rdfs-tbox1-data1": ("rdfs/tbox1.rdf", "rdfs/data1.rdf"),
    "rdfs-tbox1-data3": ("rdfs/tbox1.rdf", "rdfs/data3.rdf"),
    "owl-tbox-consistent": ("owl/tbox.owl", "owl/consistentData.rdf"),
}
_JAVA_STRING = re.compile(r'"((?:[^"\\\n]|\\.)*)"')
_CONCAT = re.compile(r'"(?:[^"\\\n]|\\.)*"(?:\s*\+\s*(?://[^\n]*\n\s*)*"(?:[^"\\\n]|\\.)*")*')


def classpath(work: Path) -> str:
    """Return Jena's classpath, with a shim for Debian's relocated Xerces messages."""
    shim = work / "shim"
    with zipfile.ZipFile(JAVA / "jena-core.jar") as jar:
        for name in jar.namelist():
            if name.startswith("org/apache/jena/ext/xerces/") and not name.endswith("/"):
                target = shim / "xerces" / name.removeprefix("org/apache/jena/ext/xerces/")
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(jar.read(name))
    skip = re.compile(
        r"-\d[^/]*\.jar$|slf4j-(jdk14|log4j12|simple|jcl|migrator)|maven3-slf4j|"
        r"log4j-over|jcl-over|jul-to"
    )
    jars = [str(j) for j in sorted(JAVA.glob("*.jar")) if not skip.search(j.name)]
    return ":".join([str(shim), *jars])


def referee(jobs: list[list[str]], work: Path) -> None:
    """Run Jena on the jobs (see Referee.java), in one JVM."""
    cp = classpath(work)
    classes = work / "classes"
    source = ROOT / "bench" / "jena_referee" / "Referee.java"
    subprocess.run(["javac", "-nowarn", "-cp", cp, "-d", str(classes), str(source)], check=True)
    listing = work / "jobs.tsv"
    for job in jobs:
        Path(job[2] if job[0] == "parse" else job[3]).unlink(missing_ok=True)
    while jobs:
        listing.write_text("".join("\t".join(job) + "\n" for job in jobs))
        done = subprocess.run(["java", "-cp", f"{classes}:{cp}", "Referee", str(listing)])
        if done.returncode not in (0, 3):
            raise SystemExit(f"the referee failed (exit status {done.returncode})")
        jobs = [j for j in jobs if not Path(j[2] if j[0] == "parse" else j[3]).exists()]


def git_show(git: Path, path: str) -> bytes:
    return subprocess.run(
        ["git", "--git-dir", str(git), "show", f"{REF}:{path}"], check=True, capture_output=True
    ).stdout


def rule_texts(git: Path) -> list[dict[str, str]]:
    """Return the rule texts written as Java strings in Jena's rule tests."""
    found = []
    for path in TEST_CLASSES:
        try:
            java = git_show(git, path).decode()
        except subprocess.CalledProcessError:
            continue
        for match in _CONCAT.finditer(java):
            text = "".join(_unescape(m.group(1)) for m in _JAVA_STRING.finditer(match.group(0)))
            if "->" in text or "<-" in text:
                line = java.count("\n", 0, match.start()) + 1
                found.append({"source": f"{Path(path).name}:{line}", "text": text})
    return found


def _unescape(text: str) -> str:
    simple = {"n": "\n", "t": "\t", "r": "\r", '"': '"', "'": "'", "\\": "\\"}

    def one(m: re.Match[str]) -> str:
        code = m.group(1)
        return chr(int(code[1:], 16)) if code[0] == "u" else simple.get(code, code)

    return re.sub(r"\\(u[0-9a-fA-F]{4}|.)", one, text)


def bundled_jobs(git: Path) -> list[list[str]]:
    """Copy Jena's bundled rule sets and test data; return the jobs that run them."""
    for folder in ("etc", "data", "expected", "texts"):
        (OUT / folder).mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(JAVA / "jena-core.jar") as jar:
        for name in jar.namelist():
            if name.startswith("etc/") and name.endswith(".rules"):
                (OUT / name).write_bytes(jar.read(name))
    for files in DATA.values():
        for file in files:
            target = OUT / "data" / file.replace("/", "-")
            target.write_bytes(git_show(git, f"jena-core/testing/reasoners/{file}"))
    jobs = []
    for rules in sorted((OUT / "etc").glob("*.rules")):
        for name, files in DATA.items():
            data = ",".join(str(OUT / "data" / f.replace("/", "-")) for f in files)
            out = OUT / "expected" / f"{rules.stem}@{name}.nt"
            jobs.append(["run", "hybrid", str(rules), str(out), data])
    return jobs


def main(git: Path | None, cases_only: bool = False) -> None:
    if git is None and not cases_only:
        raise SystemExit("--jena-git is needed (only --cases-only runs without it)")
    jobs = [] if cases_only else bundled_jobs(git)  # type: ignore[arg-type]
    for case in sorted((OUT / "cases").glob("*.json")):
        spec = json.loads(case.read_text())
        rules = case.with_suffix(".rules")
        rules.write_text(spec["rules"])
        data = case.with_suffix(".data.nt")
        data.write_text(spec.get("data", ""))
        out = case.with_suffix(".expected.nt")
        mode = spec.get("mode", "forwardRETE")
        if "steps" in spec:
            steps = case.with_suffix(".steps")
            steps.write_text("".join(line + "\n" for line in spec["steps"]))
            jobs.append(["steps", mode, str(rules), str(out), str(steps)])
        else:
            jobs.append(["run", mode, str(rules), str(out), str(data)])
    if cases_only:
        with tempfile.TemporaryDirectory() as work:
            referee(jobs, Path(work))
        print(f"recorded {len(jobs)} Jena answers into {OUT / 'cases'}")
        return
    texts = rule_texts(git)
    for old in (OUT / "texts").glob("*.rules"):
        old.unlink()
    for i, entry in enumerate(texts):
        path = OUT / "texts" / f"{i:03d}.rules"
        path.write_text(entry["text"])
        jobs.append(["parse", str(path), str(path.with_suffix(".jena"))])
    with tempfile.TemporaryDirectory() as work:
        referee(jobs, Path(work))
    for i, entry in enumerate(texts):
        verdict = OUT / "texts" / f"{i:03d}.jena"
        entry["jena"] = verdict.read_text().strip()
        verdict.unlink()
        (OUT / "texts" / f"{i:03d}.rules").unlink()
    (OUT / "texts").rmdir()
    (OUT / "rule_texts.json").write_text(json.dumps(texts, indent=1) + "\n")
    print(f"recorded {len(jobs)} Jena answers into {OUT}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jena-git", type=Path, help="apache/jena's .git")
    parser.add_argument(
        "--cases-only", action="store_true", help="rerun only the transcribed cases"
    )
    args = parser.parse_args()
    main(args.jena_git, args.cases_only)
