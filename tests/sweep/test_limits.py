"""A sweep file is bounded (issue 18, items 3 and 4, and config = "/dev/zero"): every limit is
refused at once (a few MB allocated at most: nothing expanded or read whole; how fast it is:
benchmarks/bench_limits.py), with one plain line naming the limit and how to raise it, before
anything runs; a program's output is read without bound on memory or disk, its tail kept."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.errors import SweepError
from simmer.sweep import load_sweep
from simmer.sweep.results import ResultsFile
from simmer.sweep.runs import STDERR_TAIL, RunSpec, execute
from simmer.sweep.spec import MAX_RUNS

from helpers import EXAMPLES, peak_memory

pytestmark = pytest.mark.timeout(120)

REFUSE_WITHIN = 64 * 2**20
"""Bytes a refusal may allocate at its peak (about 17 MB now): a grid of 10**12 runs built goes
far past it (memory, not time: the same on a shared machine)."""
HEAD = 'config = "robot.toml"\nprogram = "python robot.py"\n'


def refuse(tmp_path: Path, text: str, *words: str) -> int:
    """``simmer sweep`` on this sweep file: exit 1, one plain line with ``words``, nothing run;
    the most memory it allocated at once (bytes)."""
    (tmp_path / "robot.toml").write_text("")
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(text)
    args = ["sweep", str(sweep), "-o", str(tmp_path / "sweep-results")]
    result, peak = peak_memory(lambda: CliRunner().invoke(app, args))
    assert result.exit_code == 1, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(str(sweep)), lines[0]  # the file first
    for word in words:
        assert word in lines[0], lines[0]
    assert not (tmp_path / "sweep-results").exists()  # nothing ran
    assert peak < REFUSE_WITHIN, peak
    return peak


GRID_4 = "[grid]\n" + "".join(
    f'"drives.w0.error.{axis}" = {list(range(1000))}\n' for axis in ("x", "y", "rotation")
)
CASES = {
    "grid 1000^4": (
        HEAD + GRID_4 + f'"sensors.u0.error" = {list(range(1000))}\n',
        ("1,000,000,000,000 runs", f"at most {MAX_RUNS:,}", "MAX_RUNS", "docs/limits.md"),
    ),
    "count 10**12": (
        HEAD + '[sample]\ncount = 1000000000000\n"drives.w0.error.y" = {uniform = [0, 1]}\n',
        ("1,000,000,000,000 runs", "MAX_RUNS"),
    ),
    "seeds 10**12": (HEAD + "seeds = 1000000000000\n", ("1,000,000,000,000 runs", "MAX_RUNS")),
    "200,000 nots": (
        HEAD + f'success = "{"not " * 200_000}reached"\n',
        ("success: 800,007 characters", "MAX_EXPRESSION_CHARS"),
    ),
    "nested nots": (
        HEAD + f'success = "{"not " * 40}reached"\n',
        ("nested more than 32 deep", "MAX_EXPRESSION_DEPTH"),
    ),
    "key of 20,000 names": (
        HEAD + "[grid]\n" + ".".join(["a"] * 20_000) + " = [1]\n",
        ("a.a.a.a...", "more than 16 names", "MAX_KEY_PARTS"),
    ),
    "quoted key of 20,000 names": (
        HEAD + '[grid]\n"' + ".".join(["a"] * 20_000) + '" = [1]\n',
        ("more than 16 names",),
    ),
    "config /dev/zero": (
        'config = "/dev/zero"\nprogram = "python robot.py"\n',
        ("/dev/zero is not a regular file",),
    ),
    "file of 2 MB": (HEAD + "#" * 2_000_000 + "\n", ("larger than 1,000,000 bytes",)),
}


SLOW = {"200,000 nots"}
"""Cases that take seconds with their memory traced (800,000 characters parsed)."""


@pytest.mark.parametrize(
    "name", [pytest.param(name, marks=pytest.mark.slow) if name in SLOW else name for name in CASES]
)
def test_each_sweep_limit_is_refused_at_once_naming_it(tmp_path: Path, name: str) -> None:
    text, words = CASES[name]
    refuse(tmp_path, text, *words)


@pytest.mark.slow
def test_a_bad_value_in_a_large_grid_is_found_by_checking_each_value(tmp_path: Path) -> None:
    """90,000 runs: each value of each key is built once, not every combination."""
    values = [i / 1000 for i in range(300)]
    spoilt = [*values[:200], "abc", *values[201:]]  # not a number: no run can use it
    (tmp_path / "robot.toml").write_text((EXAMPLES / "lab1_rover.toml").read_text())
    (tmp_path / "sweep.toml").write_text(
        HEAD + f'[grid]\n"drives.w0.error.x" = {values}\n"drives.w0.error.y" = {spoilt}\n'
    )
    spec = load_sweep(tmp_path / "sweep.toml")
    assert spec.run_count == 90_000
    checked = list(spec.settings_to_check())
    assert len(checked) < 700
    with pytest.raises(SweepError, match=r"drives.w0.error.y = 'abc'"):
        spec.check_settings()


def test_a_run_that_floods_its_output_keeps_only_the_tail(tmp_path: Path) -> None:
    (tmp_path / "robot.toml").write_text("")
    (tmp_path / "flood.py").write_text(
        "import sys\n"
        "block = 'x' * 65535 + '\\n'\n"
        "for _ in range(3000):\n"  # some 200 MB
        "    sys.stdout.write(block)\n"
        "sys.stdout.flush()\n"
        "print('the last words', file=sys.stderr)\n"
        "sys.exit(1)\n"
    )
    run = RunSpec(
        config=str(tmp_path / "robot.toml"),
        overrides=(),
        seed=0,
        kind="program",
        controller="python flood.py",
        folder=str(tmp_path),
        wall_seconds=100,
    )
    result = execute(run)
    assert result.status == "error"
    assert result.exit_status == 1
    assert result.detail.endswith("the last words")
    assert len(result.detail) <= STDERR_TAIL


def test_resumed_results_are_data(tmp_path: Path) -> None:
    """--resume reads results.csv back: a row whose folder points out of runs/ is not taken as
    done (the filming of failures would write there), and a file that is not a table is one
    line naming it."""
    columns = ["seed", "success", "run", "folder", "detail"]
    path = tmp_path / "results.csv"
    rows = [columns, ["0", "False", "aaa", "../../outside", ""], ["1", "True", "bbb", "runs/x", ""]]
    path.write_text("".join(",".join(row) + "\n" for row in rows))
    results = ResultsFile(path, columns, resume=True)
    results.close()
    assert list(results.done) == ["bbb"]
    path.write_bytes(b"seed,success\n\xff\xfe\x00junk\n")
    with pytest.raises(ValueError, match=r"results.csv is not a results table"):
        ResultsFile(path, columns, resume=True)
