"""The quick test loop (issue 29, item 8): plain ``pytest`` leaves out what is marked slow, and
a test not marked slow that uses more than two CPU seconds fails, saying to mark it."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from helpers import REPO

BURN = """\
import pytest
from conftest import QUICK_TEST_CPU_SECONDS, cpu_seconds


def burn() -> None:
    end = cpu_seconds() + QUICK_TEST_CPU_SECONDS + 0.2
    while cpu_seconds() < end:
        pass


def test_quick() -> None:
    pass


def test_burns_unmarked() -> None:
    burn()


@pytest.mark.slow
def test_burns_marked_slow() -> None:
    burn()
"""


@pytest.mark.slow
def test_an_unmarked_test_over_two_cpu_seconds_fails(tmp_path: Path) -> None:
    shutil.copy(REPO / "tests" / "conftest.py", tmp_path)
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n    slow\n    fresh\n")
    (tmp_path / "test_burn.py").write_text(BURN)
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist"]
    result = subprocess.run(
        [*command, "-rA", str(tmp_path)], capture_output=True, text=True, cwd=tmp_path, check=False
    )
    output = result.stdout
    assert "PASSED test_burn.py::test_quick" in output, output
    assert "PASSED test_burn.py::test_burns_marked_slow" in output, output
    assert "FAILED test_burn.py::test_burns_unmarked" in output, output
    assert "mark it @pytest.mark.slow" in output, output
    assert "1 failed, 2 passed" in output, output


def test_plain_pytest_leaves_out_slow_and_fresh_tests_and_test_sh_runs_all() -> None:
    with (REPO / "pyproject.toml").open("rb") as file:
        addopts = tomllib.load(file)["tool"]["pytest"]["ini_options"]["addopts"]
    assert "-m 'not slow and not fresh'" in addopts
    assert '.venv/bin/pytest -m "" "$@"' in (REPO / "scripts" / "test.sh").read_text()
