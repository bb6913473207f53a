"""A sleep longer than the lockstep clock takes (``time.sleep(1e18)``) is refused at the call
with the limit named, as Python's own sleep refuses one past its limit; the simulator's log
names the limit for a raw ``!sleep`` too (both once said "not a clock message")."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from simmer.protocol import MAX_ABS_VALUE, parse_clock

from helpers import REPO

SHIM = REPO / "src" / "simmer" / "lockstep" / "shim" / "sitecustomize.py"

pytestmark = pytest.mark.timeout(120)

PROGRAM = """\
import time
for seconds in (1e18, float("inf"), float("nan")):
    try:
        time.sleep(seconds)
    except (OverflowError, ValueError) as exc:
        print(type(exc).__name__, exc, flush=True)
time.sleep(0.5)
print("slept to", round(time.monotonic(), 3), flush=True)
"""


@pytest.mark.slow
def test_a_huge_sleep_is_refused_in_the_program_naming_the_limit(tmp_path: Path) -> None:
    (tmp_path / "sleeper.py").write_text(PROGRAM, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "simmer", "run", "--headless", "--seconds", "60",
         "--program", f"{sys.executable} sleeper.py"],
        cwd=tmp_path, capture_output=True, text=True, timeout=90, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    refused = [line for line in lines if line.startswith("OverflowError")]
    assert len(refused) == 2, done.stdout
    assert all("MAX_SLEEP" in line for line in refused)
    assert any(line.startswith("ValueError Invalid value NaN") for line in lines)
    assert any(line.startswith("slept to 0.5") for line in lines), done.stdout


def test_a_raw_sleep_past_the_limit_names_it() -> None:
    with pytest.raises(ValueError, match="MAX_ABS_VALUE") as refused:
        parse_clock("!sleep 1e+18 @12")
    assert "not a clock message" not in str(refused.value)
    assert parse_clock(f"!sleep {MAX_ABS_VALUE:.0f}").seconds == MAX_ABS_VALUE


def test_the_shim_and_the_simulator_agree() -> None:
    """The shim's MAX_SLEEP, read from its source (importing it would run the chained
    sitecustomize of this environment)."""
    tree = ast.parse(SHIM.read_text(encoding="utf-8"))
    (value,) = (
        node.value
        for node in tree.body
        if isinstance(node, ast.Assign) and ast.unparse(node.targets[0]) == "MAX_SLEEP"
    )
    assert ast.literal_eval(value) == MAX_ABS_VALUE
