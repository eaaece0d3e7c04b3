"""The layout's one rule: imports go agents -> space, and only through space's API."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import space

ROOT = Path(__file__).resolve().parents[1]
API_MODULES = {"space", "space.reasoning"}


def imports(package: str) -> list[tuple[Path, int, str, tuple[str, ...]]]:
    """Return (file, line, module, names) for every import in `package`'s sources."""
    found = []
    for path in sorted((ROOT / package).rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                found += [(path, node.lineno, a.name, ()) for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = tuple(a.name for a in node.names)
                found.append((path, node.lineno, node.module, names))
    return found


def test_space_never_imports_agents():
    wrong = [
        f"{p.relative_to(ROOT)}:{line} {module}"
        for p, line, module, _ in imports("space")
        if module == "agents" or module.startswith("agents.")
    ]
    assert wrong == []


def test_agents_use_only_the_public_api_of_space():
    wrong = [
        f"{p.relative_to(ROOT)}:{line} {module}"
        for p, line, module, _ in imports("agents")
        if (module == "space" or module.startswith("space.")) and module not in API_MODULES
    ]
    assert wrong == []
    unlisted = [
        f"{p.relative_to(ROOT)}:{line} {name}"
        for p, line, module, names in imports("agents")
        if module == "space"
        for name in names
        if name not in space.__all__
    ]
    assert unlisted == []


def test_every_api_name_resolves():
    assert all(getattr(space, name) is not None for name in space.__all__)
    assert set(space.__all__) <= set(dir(space))


def test_the_engine_loads_without_the_zenoh_side():
    # Who reasons alone (bench/owl_rl.py, a tool) pays no memory for the client and Zenoh.
    code = "import sys, space.reasoning; "
    code += "print('zenoh' in sys.modules, 'space.client' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]
