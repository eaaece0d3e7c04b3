"""The README's shell and Python examples run as written against `tspace up`'s default space.

The examples are read from README.md itself, so they cannot drift from what is tested. They
run from a folder like the project's (its rules/ and ontology/), with `--connect` added for
the test's port (`tspace up` listens on a free one, not 7447), as tests/docexamples.py runs
them: a query that finds nothing fails.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys

from docexamples import shell_prelude
from uprun import Up

from conftest import REPO
from space.reasoning import default_registry, load_rules

README = (REPO / "README.md").read_text()


def blocks(language: str, after: str) -> list[str]:
    """Return the code blocks of a language in the README section whose title is `after`."""
    section = README.split(f"## {after}\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(rf"```{language}\n(.*?)```", section, flags=re.S)


def test_the_shell_and_python_examples_run(tmp_path):
    [shell] = blocks("sh", "The space from a shell")
    [python] = blocks("python", "From Python")
    here = tmp_path / "project"
    here.mkdir()
    for name in ("rules", "ontology"):
        (here / name).symlink_to(REPO / name)
    with Up(tmp_path, None) as up:
        up.wait_started()
        up.wait_connected("reasoner", "hw_monitor", "behavior")
        endpoint = f"tcp/127.0.0.1:{up.port}"
        code = python.replace('"tcp/127.0.0.1:7447"', repr(endpoint))
        done = subprocess.run(
            [sys.executable, "-c", code],
            cwd=here,
            capture_output=True,
            text=True,
            timeout=60,
            env={**os.environ, "PYTHONPATH": str(REPO)},
        )
        assert done.returncode == 0, done.stderr
        # The level read back is the written one or, the robot starting on its charger (where
        # a battery is never "very low"), the battery monitor's answer to it: either way one.
        assert re.search(r'ac:robot1_battery ac:battery_level "(very low|low)"', done.stdout)
        assert "selfconfig#current_task" in done.stdout, done.stdout  # the why loop ran

        done = subprocess.run(
            ["bash", "-c", shell_prelude(sys.executable, endpoint) + shell],
            cwd=here,
            capture_output=True,
            text=True,
            timeout=180,
            env={**os.environ, "PYTHONPATH": str(REPO)},
        )
        assert done.returncode == 0, f"{done.stdout}\n{done.stderr}"
        out = done.stdout
        assert "ac:robot1_battery" in out and '"head"' in out  # the two queries
        assert re.search(r"^[0-9a-f]{32}$", out, flags=re.M)  # the write's changeset id
        assert "ac:robot1_base ac:motion_speed" in out and "written by" in out  # the why
        rules = load_rules([REPO / "rules" / "selfconfig.rules"], default_registry())
        assert f"rules/selfconfig.rules: {len(rules)} rules" in out  # rules check


def test_the_readme_names_no_file_it_does_not_ship_or_make():
    [shell] = blocks("sh", "The space from a shell")
    made = set(re.findall(r"cat > (\S+)", shell))
    for path in re.findall(r"(?<![\w/])([\w/.-]+\.(?:ttl|rules|toml))\b", shell):
        assert path in made or (REPO / path).exists(), path
