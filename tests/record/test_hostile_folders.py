"""Run folders are data (issue 18, items 1, 6 and 9): replay, render and plot never import a
plug-in a folder names unless trusted, and every malformed or hostile folder is refused with one
plain line naming the file and what is wrong, at once (a few MB allocated at most: no file read
whole; how fast: benchmarks/bench_limits.py), and a spoilt report.json only after the plots it
does not spoil are drawn."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from collections.abc import Callable
from functools import partial
from pathlib import Path

import pytest
from typer.testing import CliRunner, Result

from simmer import Simulation
from simmer.cli import app
from simmer.config import load_config
from simmer.record import RunRecorder
from simmer.record.plots import read_run
from simmer.record.runfolder import MAX_RUN_SECONDS
from simmer.view.replay_model import Recording

from helpers import drive_noisily, noisy_config, peak_memory

pytestmark = pytest.mark.timeout(120)

REFUSE_WITHIN = 64 * 2**20
"""Bytes a refusal may allocate at its peak (about 17 MB now): a file of 300 MB read whole goes
far past it (memory, not time: the same on a shared machine)."""
PLUGIN = """\
from pathlib import Path
Path(__file__).with_name("MARKER").write_text("the plug-in ran")
"""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short noisy run with a reset, recorded once."""
    folder = tmp_path_factory.mktemp("hostile") / "run"
    sim = Simulation(noisy_config(), seed=5)
    with RunRecorder(sim, folder):
        drive_noisily(sim)
    return folder


@pytest.fixture
def copy(recorded: Path, tmp_path: Path) -> Path:
    target = tmp_path / "run"
    shutil.copytree(recorded, target)
    return target


def invoke(*args: str) -> Result:
    """Run ``simmer ARGS`` in this process."""
    return CliRunner().invoke(app, list(args))


def assert_one_plain_line(result: Result, *words: str) -> str:
    """Exit status 1, no traceback, and one line on stderr holding ``words``."""
    assert result.exit_code == 1, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.output
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def edit_json(path: Path, change: Callable[[dict], None]) -> None:
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))


# ----------------------------------------------------------------------------- plug-ins


def record_with_plugin(folder: Path) -> Path:
    """A run recorded with a plug-in that leaves a MARKER file beside itself when imported."""
    folder.mkdir()
    (folder / "evil.py").write_text(PLUGIN)
    (folder / "robot.toml").write_text('plugins = ["evil.py"]\n')
    sim = Simulation(load_config(folder / "robot.toml"), seed=1)
    with RunRecorder(sim, folder / "run"):
        for _ in range(30):
            sim.step()
    (folder / "MARKER").unlink()
    return folder / "run"


@pytest.mark.slow
@pytest.mark.parametrize("command", ["replay", "render", "plot"])
def test_a_plugin_a_folder_names_is_never_imported_without_trust(
    tmp_path: Path, command: str
) -> None:
    run = record_with_plugin(tmp_path / "p")
    args = [command, str(run), *(["--check"] if command == "replay" else [])]
    result = invoke(*args)
    assert not (tmp_path / "p" / "MARKER").exists()  # the plug-in's code never ran
    if command == "plot":  # a plot re-simulates nothing: it draws, and imports nothing
        assert result.exit_code == 0, result.output
    else:
        assert_one_plain_line(result, "manifest.json", "plug-ins (evil.py)", "--trust")


@pytest.mark.slow
def test_a_folder_with_plugins_is_resimulated_with_trust_or_the_plugins_named(
    tmp_path: Path,
) -> None:
    run = record_with_plugin(tmp_path / "p")
    marker = tmp_path / "p" / "MARKER"
    simmer = Path(sys.executable).with_name("simmer")  # a new process: the plug-in is new to it
    done = subprocess.run(
        [simmer, "replay", run, "--check", "--trust"],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "matches the recording" in done.stdout
    assert marker.exists()
    marker.unlink()
    mine = tmp_path / "mine.py"
    mine.write_text("")  # my own (empty) copy: the folder's plug-in stays unimported
    result = invoke("replay", str(run), "--check", "--plugin", str(mine))
    assert result.exit_code == 0, result.output
    assert not marker.exists()


# ----------------------------------------------------------------------------- malformed folders


def _manifest(change: Callable[[dict], None]) -> Callable[[Path], None]:
    return lambda folder: edit_json(folder / "manifest.json", change)


def _events(line: dict) -> Callable[[Path], None]:
    def add(folder: Path) -> None:
        with (folder / "events.jsonl").open("a") as file:
            file.write(json.dumps(line) + "\n")

    return add


def _walls(rows: int, columns: int) -> Callable[[dict], None]:
    def change(data: dict) -> None:
        data["config"]["settings"]["walls"] = [[1] * columns] * rows

    return change


def _set(*keys: str, value: object) -> Callable[[dict], None]:
    def change(data: dict) -> None:
        for key in keys[:-1]:
            data = data[key]
        data[keys[-1]] = value

    return change


COMMAND = {"type": "command", "message": "u0", "replies": [1.0], "client": "x"}
HOSTILE: dict[str, tuple[Callable[[Path], None], tuple[str, ...], tuple[str, ...]]] = {
    # name: (how the folder is spoilt, commands that must refuse it, words of the message)
    "format 99": (_manifest(_set("format", value=99)), ("replay", "plot"), ("layout 99", "newer")),
    "format text": (_manifest(_set("format", value="1")), ("replay", "plot"), ("format '1'",)),
    "manifest a list": (
        lambda f: (f / "manifest.json").write_text("[1, 2]"),
        ("replay", "plot"),
        ("manifest.json", "not a JSON object"),
    ),
    "manifest deep": (
        lambda f: (f / "manifest.json").write_text("[" * 100_000 + "]" * 100_000),
        ("replay", "plot"),
        ("manifest.json", "not readable JSON"),
    ),
    "manifest huge": (
        lambda f: (f / "manifest.json").write_text(" " * 17_000_000 + "{}"),
        ("replay", "plot"),
        ("manifest.json", "larger than"),
    ),
    "seed text": (_manifest(_set("seed", value="x")), ("replay",), ("seed 'x'",)),
    "walls 2000": (
        # 2,000 rows (the limit is 500) of 600 cells: 3.6 MB of JSON; 2,000 x 2,000 was 12 MB,
        # whose parsing alone took the whole second of CPU on a slow machine
        _manifest(_walls(2000, 600)),
        ("replay", "plot"),
        ("manifest.json: the recorded", "walls: has 2,000 rows"),
    ),
    "settings a list": (_manifest(_set("config", "settings", value=[])), ("replay", "plot"), ()),
    "step 10**12": (_events({**COMMAND, "time": 1.0, "step": 10**12}), ("replay",), ("limit",)),
    "step Infinity": (
        _events({**COMMAND, "time": 1.0, "step": math.inf}),
        ("replay",),
        ("events.jsonl line", "infinity"),
    ),
    "time 1e10": (_events({**COMMAND, "time": 1e10, "step": 5}), ("plot",), ("time 1e+10",)),
    "event a list": (_events([1]), ("replay",), ("events.jsonl line",)),  # type: ignore[arg-type]
    "event type a list": (_events({**COMMAND, "type": [1]}), ("replay",), ("unknown event type",)),
    "devices a number": (
        _manifest(_set("config", "devices", value=5)),
        ("replay",),
        ("manifest.json: not a run's manifest",),
    ),
    "events of 300 MB": (
        lambda f: _grow(f / "events.jsonl"),
        ("replay", "plot"),
        ("events.jsonl is 314,572,800 bytes, more than a recording holds",),
    ),
    "trace of 300 MB": (
        lambda f: _grow(f / "trace.csv"),
        ("replay", "plot"),
        ("trace.csv is 314,572,800 bytes",),
    ),
    "trace huge step": (
        lambda f: (f / "report.json").unlink() or _append(f / "trace.csv", "99999999999"),
        ("replay",),
        ("trace.csv", "limit"),
    ),
}

SLOW = {"walls 2000", "manifest huge"}
"""Cases that take seconds with their memory traced (a manifest of megabytes parsed)."""


def _grow(path: Path) -> None:
    """Make ``path`` 300 MB (sparse: nothing is written)."""
    with path.open("r+b") as file:
        file.truncate(300 * 2**20)


def _append(path: Path, step: str) -> None:
    header = path.read_text().splitlines()[0].split(",")
    row = ["0"] * len(header)
    row[header.index("step")] = step
    with path.open("a") as file:
        file.write(",".join(row) + "\n")


@pytest.mark.parametrize(
    "name",
    [
        pytest.param(name, marks=pytest.mark.slow) if name in SLOW else name
        for name in sorted(HOSTILE)
    ],
)
def test_a_hostile_folder_gets_one_plain_line_at_once(copy: Path, name: str) -> None:
    spoil, commands, words = HOSTILE[name]
    spoil(copy)
    for command in commands:
        args = [command, str(copy), *(["--check"] if command == "replay" else [])]
        result, peak = peak_memory(partial(invoke, *args))
        assert_one_plain_line(result, *words)
        assert peak < REFUSE_WITHIN, (command, peak)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("report", "words"),
    [('{"outcome": ', ("report.json", "JSON")), ('{"outcome": "x"}', ("report.json",))],
    ids=["corrupt report", "report of text"],
)
def test_a_spoilt_report_still_gets_its_plots_and_one_plain_line(
    copy: Path, report: str, words: tuple[str, ...]
) -> None:
    # refused after the drawing (the plots are the work asked for, so no CPU bound here)
    (copy / "report.json").write_text(report)
    result = invoke("plot", str(copy))
    line = assert_one_plain_line(result, *words)
    assert line.startswith("drew path.png and sensors.png, but not report.md"), line
    assert (copy / "path.png").stat().st_size > 0
    assert (copy / "sensors.png").stat().st_size > 0


def test_the_replay_limit_is_an_hour_by_default(copy: Path) -> None:
    steps = int(MAX_RUN_SECONDS * 60) + 600  # 10 s past the limit
    _events({**COMMAND, "time": 1.0, "step": steps})(copy)
    result = invoke("replay", str(copy), "--check")
    assert_one_plain_line(result, f"{steps:,}", "--max-seconds")


@pytest.mark.slow
def test_the_replay_limit_is_raised_by_max_seconds(copy: Path) -> None:
    """The same rule as the default's, at a limit a test can replay past in a moment."""
    steps = 90 * 60  # 90 s in (the recorded run itself is shorter than a minute)
    _events({**COMMAND, "time": 1.0, "step": steps})(copy)
    result = invoke("replay", str(copy), "--check", "--max-seconds", "60")
    assert_one_plain_line(result, f"{steps:,}", "--max-seconds")
    folder = Recording.load(copy, max_seconds=120)  # the folder is fine
    assert folder.check.reply_differences  # the made-up command's reply differs


@pytest.mark.slow
def test_a_killed_recording_claims_no_rows_its_trace_lacks(copy: Path) -> None:
    """After kill -9 the trace lacks its last rows: the check counts those it compared."""
    (copy / "report.json").unlink()
    trace = copy / "trace.csv"
    lines = trace.read_text().splitlines(keepends=True)
    kept = len(lines) // 2
    trace.write_text("".join(lines[:kept]))
    check = Recording.load(copy).check
    assert check.matches
    assert check.rows == kept - 1  # the header is not a row
    assert f"({kept - 1} trace rows" in check.headline()


@pytest.mark.slow
def test_a_trace_row_with_an_absurd_pose_is_left_out_of_the_plot(copy: Path) -> None:
    """An edited x of 1e300 printed a path length of 300 digits across the plot's title."""
    _spoil_cell(copy / "trace.csv", 20, "x", "1e300")
    _spoil_cell(copy / "trace.csv", 30, "time", "-1e12")
    rows = len((copy / "trace.csv").read_text().splitlines()) - 1
    trace = read_run(copy).trace
    assert len(trace.time) == rows - 2
    assert trace.length() < 1000
    result = invoke("plot", str(copy))
    assert result.exit_code == 0, result.output


def _spoil_cell(path: Path, line: int, column: str, value: str) -> None:
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[line].split(",")
    cells[header.index(column)] = value
    lines[line] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
