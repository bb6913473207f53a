"""A sweep stops cleanly (issue 18, items 2 and 5): SIGINT, SIGTERM or SIGHUP to ``simmer
sweep`` alone, or Ctrl-C or a closed terminal signalling its whole process group, leaves no
process of it (its workers, their programs, and the programs' children that started sessions
of their own), keeps the finished runs and ``--resume`` goes on; after
``kill -9`` of the sweep its workers notice and exit, with their programs. A ``simmer run
--program`` stops the program's detached children too."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import suppress
from pathlib import Path

import pytest

from simmer.proctree import descendants

from helpers import wait_for

pytestmark = [
    pytest.mark.timeout(240),
    pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux's /proc"),
]
STARTING = 90.0
"""Seconds a sweep's processes may take to start or to go (sweep workers import a lot)."""

SIMMER = Path(sys.executable).with_name("simmer")
PROGRAM = """\
import os, subprocess, sys
from pathlib import Path

here = Path(__file__).parent
# a child in a session of its own: out of the program's process group
child = subprocess.Popen(["sleep", "100000"], start_new_session=True)
(here / "pids" / f"child-{child.pid}").write_text("")
(here / "pids" / f"program-{os.getpid()}").write_text("")
for slot in range(2):  # the first two runs finish at once; the others run until released
    try:
        os.close(os.open(here / f"quick-{slot}", os.O_CREAT | os.O_EXCL))
        sys.exit(0)
    except FileExistsError:
        pass
while not (here / "release").exists():
    pass
"""
CHILD = b"sleep\x00100000\x00"
"""A program's detached child's command line, as ``/proc/PID/cmdline`` has it."""
SWEEP = """\
config = "robot.toml"
program = "python program.py"
seeds = 4
wall_seconds = 600
"""


def alive(pid: int) -> bool:
    """Whether ``pid`` is a running process (a zombie has exited)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2] != "Z"


def in_group(pgid: int) -> list[int]:
    """Running processes in process group ``pgid``."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            fields = stat[stat.rfind(")") + 2 :].split()
            if fields[0] != "Z" and int(fields[2]) == pgid:
                found.append(int(entry.name))
    return found


def pids(folder: Path, kind: str) -> list[int]:
    return [int(p.name.split("-")[1]) for p in (folder / "pids").glob(f"{kind}-*")]


@pytest.fixture
def sweep_folder(tmp_path: Path) -> Iterator[Path]:
    """A sweep's folder; afterwards, what a failed test left running is ended (its programs
    are released, their children killed), so that no ``sleep 100000`` outlives the test."""
    (tmp_path / "pids").mkdir()
    (tmp_path / "program.py").write_text(PROGRAM)
    (tmp_path / "robot.toml").write_text("")
    (tmp_path / "sweep.toml").write_text(SWEEP)
    yield tmp_path
    (tmp_path / "release").write_text("")
    for pid in pids(tmp_path, "child"):
        with suppress(OSError):  # still the child (not a new process with its pid) if alive
            if alive(pid) and Path(f"/proc/{pid}/cmdline").read_bytes() == CHILD:
                os.kill(pid, signal.SIGKILL)


def start_sweep(folder: Path, *extra: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [SIMMER, "sweep", folder / "sweep.toml", "-o", folder / "results", "--workers=2", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, to check that none of it is left
    )


def running_sweep(folder: Path) -> tuple[subprocess.Popen[str], set[int]]:
    """A sweep with two runs finished and two programs looping; it and every process below."""
    sweep = start_sweep(folder)
    wait_for(lambda: len(pids(folder, "program")) == 4, "four programs", STARTING)
    wait_for(lambda: len(pids(folder, "child")) == 4, "their children", STARTING)
    wait_for(lambda: len(recorded(folder)) == 2, "the two quick runs in results.csv", STARTING)
    below = descendants(sweep.pid)
    assert len(below) >= 4  # two workers, two programs (and the resource tracker)
    return sweep, below | set(pids(folder, "child")) | set(pids(folder, "program"))


def recorded(folder: Path) -> list[str]:
    """The rows of the sweep's results.csv so far (a program's exit is recorded a moment later)."""
    table = folder / "results" / "results.csv"
    return table.read_text().splitlines()[1:] if table.exists() else []


def command_line(pid: int) -> str:
    """``pid`` and its command line, to name a process a test waited for in vain."""
    try:
        words = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return f"{pid} (gone)"
    return f"{pid} {b' '.join(words).decode(errors='replace').strip()}"


def assert_all_gone(sweep: subprocess.Popen[str], below: set[int], folder: Path) -> None:
    left: list[str] = []

    def all_gone() -> bool:
        left[:] = [command_line(pid) for pid in sorted(below) if alive(pid)]
        return not left

    try:
        wait_for(all_gone, "every process of the sweep to go", STARTING)
    except pytest.fail.Exception:
        pytest.fail(f"still running after {STARTING:g} s: {left}")
    assert not in_group(sweep.pid)  # by process group: the sweep's own group is empty
    assert not descendants(sweep.pid)  # by parent: nothing below it
    assert not any(alive(pid) for pid in pids(folder, "child"))  # the detached children too


def resume_the_rest(folder: Path, runs: int) -> None:
    """Release the programs and ``--resume`` the stopped sweep (two runs recorded): it runs
    the others, and the table then has all ``runs``."""
    (folder / "release").write_text("")
    resumed = start_sweep(folder, "--resume")
    stdout, stderr = resumed.communicate(timeout=150)
    assert resumed.returncode == 0, stderr
    assert f"({runs - 2} run now" in stdout
    assert len(recorded(folder)) == runs


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_signalled_sweep_stops_everything_keeps_results_and_resumes(
    sweep_folder: Path, signum: int
) -> None:
    sweep, below = running_sweep(sweep_folder)
    os.kill(sweep.pid, signum)  # the sweep alone, as `kill` or a closed terminal does
    _, stderr = sweep.communicate(timeout=90)
    assert sweep.returncode == 128 + signum, stderr
    name = signal.Signals(signum).name
    assert f"stopped ({name})" in stderr
    assert "--resume goes on" in stderr
    assert "Traceback" not in stderr
    assert_all_gone(sweep, below, sweep_folder)
    assert len(recorded(sweep_folder)) == 2  # the two runs that finished
    resume_the_rest(sweep_folder, runs=4)


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGHUP])
def test_a_signal_to_the_sweeps_process_group_stops_every_program(
    sweep_folder: Path, signum: int
) -> None:
    """Ctrl-C (SIGINT) or closing the terminal (SIGHUP) signals the sweep's whole process
    group: each worker gets the terminal's signal, then the SIGINT the sweep sends it, which
    must not cut short its stopping of its program's tree (a detached child was left)."""
    sweep, below = running_sweep(sweep_folder)
    os.killpg(sweep.pid, signum)  # as the terminal does: the sweep and its workers
    _, stderr = sweep.communicate(timeout=90)
    assert sweep.returncode == 128 + signum, stderr
    assert "--resume goes on" in stderr
    assert "died unexpectedly" not in stderr, stderr  # multiprocessing's resource tracker
    assert "Traceback" not in stderr, stderr
    assert_all_gone(sweep, below, sweep_folder)
    assert len(recorded(sweep_folder)) == 2


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")
def test_a_stopped_sweep_starts_none_of_its_queued_runs(sweep_folder: Path) -> None:
    """Six runs on two workers: when the sweep stops, two runs are queued behind the two in
    progress; a worker that took one after the stop ran it to its wall limit (600 s here)."""
    sweep_toml = sweep_folder / "sweep.toml"
    sweep_toml.write_text(sweep_toml.read_text().replace("seeds = 4", "seeds = 6"))
    sweep, below = running_sweep(sweep_folder)
    os.kill(sweep.pid, signal.SIGINT)
    _, stderr = sweep.communicate(timeout=90)
    assert sweep.returncode == 128 + signal.SIGINT, stderr
    assert_all_gone(sweep, below, sweep_folder)
    assert len(pids(sweep_folder, "program")) == 4  # no program began after the stop
    assert len(recorded(sweep_folder)) == 2
    resume_the_rest(sweep_folder, runs=6)


@pytest.mark.slow
def test_the_workers_of_a_killed_sweep_exit_with_their_programs(sweep_folder: Path) -> None:
    sweep, below = running_sweep(sweep_folder)
    sweep.kill()  # SIGKILL: the sweep cannot clean up; its workers notice it is gone
    sweep.communicate(timeout=30)
    assert_all_gone(sweep, below, sweep_folder)


@pytest.mark.slow
def test_a_run_stops_the_children_its_program_detached(tmp_path: Path) -> None:
    program = tmp_path / "detach.py"
    program.write_text(
        "import subprocess, sys\n"
        "child = subprocess.Popen(['sleep', '100000'], start_new_session=True)\n"
        f"open({str(tmp_path / 'child')!r}, 'w').write(str(child.pid))\n"
    )
    done = subprocess.run(
        [SIMMER, "run", "--headless", "--program", f"python {program}"],
        check=False,
        capture_output=True,
        text=True,
        timeout=90,
    )
    assert done.returncode == 0, done.stderr
    child = int((tmp_path / "child").read_text())
    assert not alive(child)


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")
def test_a_closed_terminal_stops_a_dask_sweep_with_no_traceback_or_library_chatter(
    sweep_folder: Path,
) -> None:
    """SIGHUP to the process group of a sweep on a local Dask cluster: it stops as the local
    pool's does, and its output holds no traceback (multiprocessing's resource tracker,
    killed by the hangup, was started again and printed one a semaphore) and none of Dask's
    INFO lines (34 of them on a sweep's terminal)."""
    pytest.importorskip("distributed")
    (sweep_folder / "wait.py").write_text(
        "import os\nfrom pathlib import Path\n"
        "here = Path(__file__).parent\n"
        "(here / 'pids' / f'program-{os.getpid()}').write_text('')\n"
        "while not (here / 'release').exists():\n    pass\n"
    )
    (sweep_folder / "sweep.toml").write_text(SWEEP.replace("program.py", "wait.py"))
    sweep = start_sweep(sweep_folder, "--engine", "dask")
    wait_for(lambda: len(pids(sweep_folder, "program")) == 2, "two programs", STARTING)
    os.killpg(sweep.pid, signal.SIGHUP)
    _, stderr = sweep.communicate(timeout=90)
    assert sweep.returncode == 128 + signal.SIGHUP, stderr
    assert "--resume goes on" in stderr
    assert "Traceback" not in stderr, stderr
    assert "INFO distributed" not in stderr, stderr
    wait_for(lambda: not in_group(sweep.pid), "the sweep's process group to empty", STARTING)
