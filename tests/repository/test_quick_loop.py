"""The quick test loop (issue 29, item 8): plain ``pytest`` leaves out what is marked slow, and
a test not marked slow that uses more than two CPU seconds there (four when every test runs)
fails, saying to mark it."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from helpers import REPO

BURN = """\
import pytest
from conftest import QUICK_TEST_CPU_SECONDS, WHOLE_SUITE_CPU_SECONDS, cpu_seconds


def burn() -> None:
    end = cpu_seconds() + QUICK_TEST_CPU_SECONDS + 0.2
    while cpu_seconds() < end:
        pass


def burn_more() -> None:
    end = cpu_seconds() + WHOLE_SUITE_CPU_SECONDS + 0.2
    while cpu_seconds() < end:
        pass


def test_quick() -> None:
    pass


def test_burns_unmarked() -> None:
    burn()


def test_burns_more_unmarked() -> None:
    burn_more()


@pytest.mark.slow
def test_burns_marked_slow() -> None:
    burn()
"""


def _run_burn(folder: Path, *options: str) -> str:
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist"]
    result = subprocess.run(
        [*command, "-rA", *options, str(folder)],
        capture_output=True,
        text=True,
        cwd=folder,
        check=False,
    )
    return result.stdout


@pytest.mark.slow
def test_an_unmarked_test_over_its_cpu_bound_fails(tmp_path: Path) -> None:
    shutil.copy(REPO / "tests" / "conftest.py", tmp_path)
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n    slow\n    fresh\n")
    (tmp_path / "test_burn.py").write_text(BURN)

    quick = _run_burn(tmp_path, "-m", "not slow and not fresh", "-k", "not more")
    assert "PASSED test_burn.py::test_quick" in quick, quick
    assert "FAILED test_burn.py::test_burns_unmarked" in quick, quick
    assert "more than QUICK_TEST_CPU_SECONDS (2)" in quick, quick
    assert "mark it @pytest.mark.slow" in quick, quick
    assert "1 failed, 1 passed, 2 deselected" in quick, quick

    whole = _run_burn(tmp_path)
    assert "PASSED test_burn.py::test_burns_unmarked" in whole, whole
    assert "PASSED test_burn.py::test_burns_marked_slow" in whole, whole
    assert "FAILED test_burn.py::test_burns_more_unmarked" in whole, whole
    assert "more than WHOLE_SUITE_CPU_SECONDS (4)" in whole, whole
    assert "1 failed, 3 passed" in whole, whole


def test_plain_pytest_leaves_out_slow_and_fresh_tests_and_test_sh_runs_all() -> None:
    with (REPO / "pyproject.toml").open("rb") as file:
        addopts = tomllib.load(file)["tool"]["pytest"]["ini_options"]["addopts"]
    assert "-m 'not slow and not fresh'" in addopts
    assert '.venv/bin/pytest -m "" "$@"' in (REPO / "scripts" / "test.sh").read_text()


SIGINT_SENT = re.compile(r"(send_signal|os\.kill|killpg|raise_signal)\([^)]*SIGINT")


def test_every_test_file_that_sends_sigint_takes_the_ctrl_c_fixture() -> None:
    """A process started while pytest has SIGINT ignored (started by ``nohup`` or ``cmd &``
    in a script) ignores SIGINT too, unless the test takes ``ctrl_c``: a server a test
    stopped with SIGINT then ran on, and the test failed on its timeout."""
    missing = [
        path.relative_to(REPO).as_posix()
        for path in sorted((REPO / "tests").rglob("*.py"))
        if SIGINT_SENT.search(text := path.read_text(encoding="utf-8")) and "ctrl_c" not in text
    ]
    assert missing == []
