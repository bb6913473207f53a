"""The set-up scripts and the documentation: the scripts set up and then work, and the docs say
that configurations run code."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
from pathlib import Path

import pytest

from helpers import REPO


def fake_repo(tmp_path: Path, script: str) -> tuple[Path, Path]:
    """A copy of ``scripts/<script>`` in a repository whose python3, pip and tools only log
    what they are asked to do; returns the script and the log."""
    repo = tmp_path / "repo"
    (repo / "scripts").mkdir(parents=True)
    shutil.copy(REPO / "scripts" / script, repo / "scripts" / script)
    (repo / "pyproject.toml").write_text("[project]\nname = 'simmer'\n", encoding="utf-8")
    calls = tmp_path / "calls.log"
    fake = f'#!/usr/bin/env bash\necho "$(basename "$0") $*" >> {calls}\n'
    venv_bin = repo / ".venv" / "bin"
    path_bin = tmp_path / "bin"
    venv_bin.mkdir(parents=True)
    path_bin.mkdir()
    for directory, names in ((venv_bin, ("python", "simmer", "ruff", "mypy", "pytest")),
                             (path_bin, ("python3",))):  # fmt: skip
        for name in names:
            tool = directory / name
            tool.write_text(fake, encoding="utf-8")
            tool.chmod(tool.stat().st_mode | stat.S_IEXEC)
    return repo / "scripts" / script, calls


@pytest.mark.skipif(shutil.which("bash") is None, reason="the scripts are bash")
@pytest.mark.parametrize(
    ("script", "expected"),
    [
        ("run.sh", ["python3 scripts/setup.py", "simmer run --speed 2"]),
        ("test.sh", ["python3 scripts/setup.py --test", "ruff check .", "ruff format --check .",
                     "mypy", "pytest -m  --speed 2"]),
    ],
)  # fmt: skip
def test_scripts_set_up_then_work(tmp_path: Path, script: str, expected: list[str]) -> None:
    """The set-up itself (only when needed) is scripts/setup.py's, tested in
    repository/test_fresh_clone.py."""
    path, calls = fake_repo(tmp_path, script)
    env = {**os.environ, "PATH": f"{tmp_path / 'bin'}{os.pathsep}{os.environ['PATH']}"}
    subprocess.run(["bash", str(path), "--speed", "2"], env=env, check=True, capture_output=True)
    assert [line.strip() for line in calls.read_text(encoding="utf-8").splitlines()] == expected


def test_docs_say_that_configurations_run_code() -> None:
    for doc in ("README.md", "docs/migrating.md", "docs/devices.md"):
        text = " ".join((REPO / doc).read_text(encoding="utf-8").split())
        assert "configurations you trust" in text, doc
