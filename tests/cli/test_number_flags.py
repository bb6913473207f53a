"""Numeric flags are checked before they are used: finite, in range, one plain line naming the
flag and its limit (``--seconds nan`` ran no step and reported success; ``--headings
-1e308:1e308:1e307`` and ``--record-limit inf`` ended in an OverflowError)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app

from helpers import FREE_PORTS, run_simmer


@pytest.mark.parametrize("value", ["-1", "nan", "inf", "1e308", "0"])
def test_seconds_must_be_a_positive_finite_number(tmp_path: Path, value: str) -> None:
    done = run_simmer("run", "--headless", "--seconds", value, *FREE_PORTS, cwd=tmp_path)
    assert done.returncode == 2
    assert "--seconds" in done.stderr
    assert "MAX_SIMULATED_SECONDS" in done.stderr
    assert "Traceback" not in done.stderr


@pytest.mark.parametrize(
    ("flag", "value", "limit"),
    [
        ("--link-delay", "nan", "MAX_SIMULATED_SECONDS"),
        ("--link-delay", "-0.5", "MAX_SIMULATED_SECONDS"),
        ("--timeout", "inf", "MAX_WALL_SECONDS"),
        ("--timeout", "nan", "MAX_WALL_SECONDS"),
        ("--record-limit", "inf", "MAX_RECORD_LIMIT_MB"),
        ("--record-limit", "nan", "MAX_RECORD_LIMIT_MB"),
        ("--speed", "1e-300", "SPEED_RANGE"),
        ("--speed", "1e308", "SPEED_RANGE"),
    ],
)
def test_run_flags_are_finite_and_bounded(flag: str, value: str, limit: str) -> None:
    result = CliRunner().invoke(app, ["run", "--headless", flag, value, *FREE_PORTS])
    assert result.exit_code == 2
    assert limit in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)


@pytest.mark.parametrize("value", ["0", "1000000"])
def test_sweep_workers_are_bounded(tmp_path: Path, value: str) -> None:
    result = CliRunner().invoke(app, ["sweep", str(tmp_path / "x.toml"), "--workers", value])
    assert result.exit_code == 2
    assert "MAX_WORKERS" in result.output


@pytest.mark.parametrize(
    ("headings", "step", "said"),
    [
        ("-1e308:1e308:1e307", "1", "MAX_HEADING_DEGREES"),
        ("0:360:5e-324", "1", "MAX_HEADINGS"),
        ("0:360:90", "5e-324", "MAX_TABLE_VALUES"),
        ("0:360:90", "1e308", "leaves no position"),
    ],
)
def test_table_ranges_are_checked_before_arithmetic(
    tmp_path: Path, headings: str, step: str, said: str
) -> None:
    done = run_simmer(
        "table", f"--headings={headings}", f"--step={step}", "-o", "t.npz", cwd=tmp_path
    )
    assert done.returncode == 1
    assert said in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "t.npz").exists()
