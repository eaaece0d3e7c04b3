"""The shell and Python examples of docs/*.md run as written against `tspace up`'s default space.

The examples are read from the docs themselves (tests/docexamples.py), each doc's in order in
a folder of its own like the project's (rules/, ontology/, deploy/), so an example that needs a
file must find it shipped or make it. `--connect` is added, and `tcp/127.0.0.1:7447` replaced,
for the test's port. A block marked `no-run: why` is not run: they need several hosts, an etcd
cluster, network namespaces, a ROS 2 robot or a long benchmark, or run until Ctrl-C.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from docexamples import fenced, shell_prelude
from uprun import Up

from conftest import REPO

DOCS = sorted((REPO / "docs").glob("*.md"))
RUN = [p.name for p in DOCS if any(b.runs for b in fenced(p))]


def test_every_fence_names_its_language_and_every_skipped_example_says_why():
    blocks = [b for p in DOCS for b in fenced(p)]
    assert [str(b) for b in blocks if not b.language] == []
    assert [str(b) for b in blocks if b.no_run == ""] == []
    assert sum(b.runs for b in blocks) >= 8  # the docs do have examples that run


@pytest.fixture(scope="module")
def up(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Up]:
    with Up(tmp_path_factory.mktemp("up"), None) as running:
        running.wait_started()
        running.wait_connected("reasoner", "hw_monitor", "nav_monitor", "behavior")
        yield running


@pytest.mark.parametrize("doc", RUN)
def test_the_examples_of_a_doc_run(doc: str, up: Up, tmp_path: Path) -> None:
    here = tmp_path / "project"
    here.mkdir()
    for name in ("rules", "ontology", "deploy"):
        (here / name).symlink_to(REPO / name)
    endpoint = f"tcp/127.0.0.1:{up.port}"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    for block in fenced(REPO / "docs" / doc):
        if not block.runs:
            continue
        code = block.code.replace("tcp/127.0.0.1:7447", endpoint)
        if block.language == "sh":
            argv = ["bash", "-c", shell_prelude(sys.executable, endpoint) + code]
        else:
            argv = [sys.executable, "-c", code]
        done = subprocess.run(argv, cwd=here, capture_output=True, text=True, timeout=120, env=env)
        assert done.returncode == 0, f"{block} failed:\n{done.stdout}\n{done.stderr}"
