"""Find Jena's own rule sets, which `@include <RDFS>`, `<OWL>`, `<OWLMicro>`, `<OWLMini>` name.

They are read from Jena's jar (`jena-core*.jar`, which holds them as `etc/*.rules`):
the one named by `TSPACE_JENA_CORE`, else Debian's `libapache-jena-java` in
/usr/share/java, else one under `$JENA_HOME/lib`. tspace does not ship them.
"""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

from space.reasoning.checks import located
from space.reasoning.errors import RuleSyntaxError
from space.reasoning.rules import Location

RULESETS = {
    "rdfs": "etc/rdfs-fb.rules",
    "owl": "etc/owl-fb.rules",
    "owlmicro": "etc/owl-fb-micro.rules",
    "owlmini": "etc/owl-fb-mini.rules",
}


def is_builtin_ruleset(name: str) -> bool:
    """Tell whether `@include <name>` names one of Jena's rule sets (case does not matter)."""
    return name.lower() in RULESETS


def read_builtin_ruleset(name: str, where: Location | None) -> tuple[str, str]:
    """Return the text of a Jena rule set and a name for it (`jar!/etc/x.rules`).

    Raises:
        RuleSyntaxError: no Jena jar holding it can be found.
    """
    entry = RULESETS[name.lower()]
    for jar in _jars():
        try:
            with zipfile.ZipFile(jar) as archive:
                text = archive.read(entry).decode("utf-8")
        except (OSError, KeyError, zipfile.BadZipFile):
            continue
        return text, f"{jar}!/{entry}"
    message = (
        f"@include <{name}> needs Jena's {entry}: install Jena (Debian: libapache-jena-java)"
        " or set TSPACE_JENA_CORE to a jena-core jar"
    )
    raise RuleSyntaxError(located(where, None, message))


def _jars() -> list[Path]:
    jars = []
    if named := os.environ.get("TSPACE_JENA_CORE"):
        jars.append(Path(named))
    jars.append(Path("/usr/share/java/jena-core.jar"))
    if home := os.environ.get("JENA_HOME"):
        jars.extend(sorted(Path(home, "lib").glob("jena-core*.jar")))
    return jars
