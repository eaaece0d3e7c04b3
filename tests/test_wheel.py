"""A wheel works: built from a copy, installed (not editable), `tspace up` runs from anywhere."""

from __future__ import annotations

import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from conftest import REPO, free_port


def source_copy(dest: Path) -> Path:
    """Copy the project's files (tracked or new, not ignored), as a user's checkout holds them."""
    listed = subprocess.run(
        ["git", "-C", str(REPO), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        capture_output=True,
        check=True,
    ).stdout.decode()
    for name in filter(None, listed.split("\0")):
        source = REPO / name
        if not source.exists() and not source.is_symlink():
            continue  # deleted in the work tree
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        if source.is_symlink():
            target.symlink_to(source.readlink())
        else:
            shutil.copy2(source, target)
    return dest


def installed_venv(tmp: Path) -> Path:
    """Build a wheel from a copy and install it alone in a new venv; return the venv.

    The venv sees this interpreter's dependencies through a .pth line (no registry needed)
    but not its editable tspace: a folder named in a .pth file has its own .pth files ignored.
    """
    if shutil.which("git") is None:
        pytest.skip("needs git to list the project's files")
    copy = source_copy(tmp / "src")
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp / "dist"), "."],
        cwd=copy,
        check=True,
        timeout=300,
    )
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    site = next((venv / "lib").glob("python3*/site-packages"))
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    wheel = next((tmp / "dist").glob("tspace-*.whl"))
    pip = [sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python")]
    subprocess.run(
        [*pip, "install", "-q", "--no-deps", str(wheel)],
        check=True,
        timeout=300,
    )
    return venv


def test_the_installed_wheel_plays_the_battery_scenario_from_another_directory(tmp_path):
    venv = installed_venv(tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    where = subprocess.run(
        [venv / "bin" / "python", "-c", "import agents, space; print(agents.__file__)"],
        cwd=elsewhere,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert str(venv) in where and str(REPO) not in where
    listen, data = f"tcp/127.0.0.1:{free_port()}", str(tmp_path / "data")
    up = subprocess.run(
        [
            *(venv / "bin" / "tspace", "up", "--scenario", "battery", "--once"),
            *("--listen", listen, "--data", data, "--hmi-port", str(free_port())),
        ],
        cwd=elsewhere,
        capture_output=True,
        text=True,
        timeout=400,
    )
    assert up.returncode == 0, up.stderr[-3000:]
    assert "scenario battery: completed" in up.stdout
