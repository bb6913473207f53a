"""The first hour of a new user: ``simmer new``, help pages as written, a CLI that loads no
compiler to answer ``--help``, an honest start-up line, ``wait_idle()`` without busy polls,
and ``--video`` that keeps an existing file."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from link_support import serving
from simmer.cli import app
from simmer.client import connect
from simmer.config import load_config, summarize, with_settings
from simmer.newfolder import new_folder
from simmer.world import Simulation
from simmer.world.outcome import Outcome

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
TEMPLATE = REPO / "src/simmer/data/new"
COMMANDS = [
    "new",
    "check",
    "keys",
    "run",
    "convert",
    "export-map",
    "table",
    "plot",
    "replay",
    "render",
    "sweep",
    "console",
]
PORTS = ["--port", "0", "--port-rx", "0", "--port-tx", "0"]


# ----------------------------------------------------------------------------- simmer new


def test_simmer_new_makes_a_lab_folder_whose_files_are_the_examples(tmp_path: Path) -> None:
    folder = tmp_path / "lab1"
    result = CliRunner().invoke(app, ["new", str(folder)])
    assert result.exit_code == 0, result.output
    names = sorted(path.name for path in folder.iterdir())
    assert names == [
        "README.md",
        "dead_reckoning.py",
        "my_rover.toml",
        "obstacle_avoidance.py",
        "sweep_dead_reckoning.toml",
        "sweep_obstacle_avoidance.toml",
    ]
    for copy, original in (
        ("my_rover.toml", "lab1_rover.toml"),
        ("dead_reckoning.py", "dead_reckoning.py"),
        ("obstacle_avoidance.py", "obstacle_avoidance.py"),
    ):  # one program and one rover, whichever folder a student starts from
        assert (folder / copy).read_bytes() == (EXAMPLES / original).read_bytes(), copy
    readme = (folder / "README.md").read_text(encoding="utf-8")
    assert str(REPO / "docs" / "lab1.md") in readme
    assert "{lab_page}" not in readme
    assert "simmer check my_rover.toml" in result.output
    assert (
        load_config(folder / "my_rover.toml").settings
        == load_config(EXAMPLES / "lab1_rover.toml").settings
    )


def test_the_new_folders_sweep_files_name_its_own_rover_and_programs() -> None:
    for name in ("sweep_dead_reckoning.toml", "sweep_obstacle_avoidance.toml"):
        text = (TEMPLATE / name).read_text(encoding="utf-8")
        assert 'config = "my_rover.toml"' in text
        program = re.search(r'^program = "python -u (\w+\.py)"', text, re.M)
        assert program is not None
        assert (TEMPLATE / program.group(1)).is_file()


def test_simmer_new_changes_nothing_in_a_folder_with_files(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("mine", encoding="utf-8")
    result = CliRunner().invoke(app, ["new", str(tmp_path)])
    assert result.exit_code == 1
    assert "a folder with files in it already" in result.output
    assert [path.name for path in tmp_path.iterdir()] == ["notes.txt"]
    (tmp_path / "empty").mkdir()
    assert len(new_folder(tmp_path / "empty")) == 6  # an empty folder is fine


def test_simmer_new_copies_only_the_templates_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An installed package has a __pycache__ beside the example programs: not copied."""
    package = tmp_path / "package"
    template = package / "data" / "new"
    (template / "__pycache__").mkdir(parents=True)
    (template / "README.md").write_text("see {lab_page}", encoding="utf-8")
    monkeypatch.setattr("simmer.newfolder.files", lambda _: package)
    written = new_folder(tmp_path / "lab1")
    assert [path.name for path in written] == ["README.md"]
    assert "{lab_page}" not in written[0].read_text(encoding="utf-8")


# ----------------------------------------------------------------------------- help pages


@pytest.mark.parametrize("command", COMMANDS)
def test_each_help_page_is_as_written_with_an_example(command: str) -> None:
    result = CliRunner().invoke(app, [command, "--help"], terminal_width=100)
    assert result.exit_code == 0
    text = result.output
    assert "Example:\n" in text
    assert f"    simmer {command}" in text
    for typer_marks in ("<bool>", "<str>", "<path>", "<int", "{config", "--no-"):
        assert typer_marks not in text, typer_marks


def test_brackets_in_help_are_kept() -> None:
    result = CliRunner().invoke(app, ["console", "--help"], terminal_width=100)
    assert "([u0] -> [u0:15.45])" in " ".join(result.output.split())


def test_the_command_list_says_each_command_in_one_whole_line() -> None:
    result = CliRunner().invoke(app, ["--help"], terminal_width=80)
    lines = result.output.split("Commands:\n")[1].splitlines()
    listed = [line.split()[0] for line in lines if line.strip()]
    assert listed == COMMANDS  # one line each: nothing wrapped onto a line of its own
    assert not any(line.rstrip().endswith("...") for line in lines)


HEAVY = ("numba", "numpy", "pygame", "pydantic", "matplotlib", "av")


@pytest.mark.parametrize("command", [[], ["run"], ["sweep"]])
def test_help_loads_nothing_heavy(command: list[str]) -> None:
    probe = (
        "import sys\n"
        "from simmer.cli import app\n"
        "try:\n"
        f"    app({[*command, '--help']!r}, prog_name='simmer')\n"
        "except SystemExit:\n"
        "    pass\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=60
    )
    assert "Usage: simmer" in done.stdout
    assert done.stderr.strip() == "[]"


def test_the_event_types_and_the_client_load_no_compiler() -> None:
    probe = (
        "import sys, simmer.world.events, simmer.client;"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=60
    )
    assert done.stdout.strip() == "[]"


# ----------------------------------------------------------------------------- start-up line


def test_the_start_up_line_says_which_devices_are_noisy(tmp_path: Path) -> None:
    quiet = load_config(EXAMPLES / "lab1_rover.toml")
    assert "Noise: none (every error and bias is 0)." in summarize(quiet)
    text = (EXAMPLES / "lab1_rover.toml").read_text(encoding="utf-8")
    text = text.replace("# error = { x = 0.02", "error = { x = 0.02", 1)
    text = text.replace("error = 0 ", "error = 0.02 ", 1)  # u0 only
    noisy = tmp_path / "noisy.toml"
    noisy.write_text(text, encoding="utf-8")
    loaded = load_config(noisy)
    assert "Noise: w0 error, u0 error; repeatable, seed 5489." in summarize(loaded)
    assert "Noise: w0 error, u0 error; repeatable, seed 7." in summarize(loaded, seed=7)
    fresh = with_settings(loaded, {"rand_error": True})
    assert "fresh each run (this run's: seed 12)." in summarize(fresh, seed=12)
    drawn = with_settings(quiet, {"rand_bias": True})
    assert "Noise: w0 bias, r0 bias; repeatable, seed 5489; drive biases drawn" in summarize(drawn)


def test_a_program_run_names_only_the_ports_it_serves() -> None:
    result = CliRunner().invoke(
        app,
        ["run", str(EXAMPLES / "lab1_rover.toml"), "--headless", "--seconds", "0.2",
         "--program", f"{sys.executable} -c pass"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    served = re.search(r"rx (\d+), tx (\d+)", result.output)
    assert served is not None
    assert int(served.group(1)) != 61200
    assert "61200" not in result.output
    assert "61201" not in result.output
    assert "Noise: none" in result.output


# ----------------------------------------------------------------------------- wait_idle


def test_wait_idle_in_real_time_waits_on_the_simulator_without_busy_polls() -> None:
    sim = Simulation.from_config()
    outcome = Outcome.attach(sim)
    with serving(sim, speed=1.0) as (_, link), connect(port=link.stream.port) as robot:
        assert robot.drive("w0", 1) == math.inf  # a sixth of a second of motion
        robot.wait_idle()
        assert robot.drive("w0", 0) == math.inf  # done: accepted at once
    report = outcome.report()  # the loop thread has stopped
    assert (report.busy_replies, report.nan_replies) == (0, 0)
    assert report.messages == 3  # w0-1, the one w0-0 that confirms the wait, and ours
    assert sim.robot.pose.y == pytest.approx(41.0)


# ----------------------------------------------------------------------------- --video


def test_video_keeps_an_existing_file_unless_forced(tmp_path: Path) -> None:
    path = tmp_path / "task1.mp4"
    path.write_bytes(b"last week's recording")
    run = [sys.executable, "-m", "simmer", "run", "--headless", "--seconds", "0.1", *PORTS]
    kept = subprocess.run(
        [*run, "--video", str(path)], capture_output=True, text=True, check=False, timeout=60
    )
    assert kept.returncode == 1
    assert f"the video {path} exists already" in kept.stderr
    assert "--force" in kept.stderr
    assert path.read_bytes() == b"last week's recording"
    forced = subprocess.run(
        [*run, "--video", str(path), "--force"],
        capture_output=True,
        text=True,
        check=False,
        timeout=60,
    )
    assert forced.returncode == 0, forced.stderr
    assert path.read_bytes()[4:8] == b"ftyp"  # an MP4 now


def test_report_md_defines_reached_and_the_stopwatch(tmp_path: Path) -> None:
    from simmer.record import RunRecorder

    sim = Simulation.from_config(seed=1)
    with RunRecorder(sim, tmp_path / "run"):
        sim.command("w0-6")
        sim.command("w0-0")  # busy
        sim.run_until_idle()
    report = (tmp_path / "run" / "report.md").read_text(encoding="utf-8")
    assert "within 1 in of the block's" in report
    assert "first motion" in report
    assert "| Busy replies (a drive still moving), NaN replies | 1, 0 |" in report
    outcome = json.loads((tmp_path / "run" / "report.json").read_text(encoding="utf-8"))
    assert outcome["outcome"]["busy_replies"] == 1
