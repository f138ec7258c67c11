"""scripts/python-tests, run in a copy of the repository's layout with stand-ins for
cargo and the virtual environment: which server binary it hands the tests."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess

from .conftest import REPO


def stand_in(path, body: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("#!/bin/sh\n" + body + "\n")
    path.chmod(path.stat().st_mode | stat.S_IXUSR)


def binary_chosen(tmp_path, **env: str) -> tuple[str, bool]:
    """The FIELDHOUSE_BIN the script runs pytest with, and whether it ran cargo."""
    repo = tmp_path / "repo"
    (repo / "scripts").mkdir(parents=True, exist_ok=True)
    shutil.copy(REPO / "scripts" / "python-tests", repo / "scripts" / "python-tests")
    # pip and ruff do nothing; "python -m pytest" prints the binary it was handed.
    for tool in ("pip", "ruff"):
        stand_in(repo / "target" / "python-venv" / "bin" / tool, "exit 0")
    stand_in(repo / "target" / "python-venv" / "bin" / "python", 'echo "$FIELDHOUSE_BIN"')
    stand_in(tmp_path / "bin" / "cargo", f"touch {tmp_path}/cargo-ran")
    environ = {
        k: v for k, v in os.environ.items() if k not in ("FIELDHOUSE_BIN", "CARGO_TARGET_DIR")
    }
    environ["PATH"] = f"{tmp_path / 'bin'}:{environ['PATH']}"
    run = subprocess.run(
        [str(repo / "scripts" / "python-tests")],
        env={**environ, **env},
        cwd=tmp_path,  # not the repository: a relative CARGO_TARGET_DIR is the workspace's
        capture_output=True,
        text=True,
        check=True,
    )
    return run.stdout.strip(), (tmp_path / "cargo-ran").exists()


def test_python_tests_finds_the_binary_where_cargo_target_dir_puts_it(tmp_path):
    repo = tmp_path / "repo"
    assert binary_chosen(tmp_path) == (f"{repo}/target/debug/fieldhouse", True)
    relative = binary_chosen(tmp_path, CARGO_TARGET_DIR="build/cargo")
    assert relative == (f"{repo}/build/cargo/debug/fieldhouse", True)
    elsewhere = tmp_path / "shared-target"
    assert binary_chosen(tmp_path, CARGO_TARGET_DIR=str(elsewhere)) == (
        f"{elsewhere}/debug/fieldhouse",
        True,
    )


def test_python_tests_builds_nothing_when_given_a_binary(tmp_path):
    given = binary_chosen(tmp_path, FIELDHOUSE_BIN="/opt/fieldhouse", CARGO_TARGET_DIR="x")
    assert given == ("/opt/fieldhouse", False)
