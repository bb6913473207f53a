"""``serve``: stop signals end a run cleanly, wherever they land."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import pytest
from typer.testing import CliRunner

from link_support import launch, output, run_program, stop
from simmer import serve as serving
from simmer.cli import app
from simmer.lockstep import Program
from simmer.proctree import descendants
from simmer.record import EventLog, TraceWriter
from simmer.world import Simulation

from helpers import wait_for

pytestmark = pytest.mark.timeout(60)


@pytest.mark.slow
@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_stop_cleanly_and_remove_the_serial_link(
    tmp_path: Path, how: signal.Signals
) -> None:
    link_path = tmp_path / "robot"
    proc = launch(tmp_path, "--serial-link", str(link_path))
    try:
        assert link_path.is_symlink()
        assert stop(proc, how) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert not link_path.is_symlink()
    assert not link_path.exists()
    assert "stopped" in output(tmp_path)


class _DiesWithASignal:
    """An object whose finalizer is where a stop signal lands."""

    def __del__(self) -> None:
        os.kill(os.getpid(), signal.SIGTERM)
        sum(range(1000))  # the handler runs between these bytecodes, inside the finalizer


def test_a_stop_signal_landing_in_a_finalizer_still_stops_the_run() -> None:
    """An exception raised from a finalizer is ignored by Python: once, under load, SIGTERM
    landed in one of Numba's while the handler raised KeyboardInterrupt, and the run never
    stopped. The handler now only sets the stop event and wakes the loop."""
    stop, woken, received = serving.RunStop(), [], []
    restore = serving._stop_on_signals(stop, lambda: woken.append(True), received)
    try:
        _DiesWithASignal()  # collected at once: the signal arrives in its __del__
    finally:
        restore()
    assert stop.is_set()
    assert woken == [True]
    assert received == ["SIGTERM"]


def test_a_stop_signal_landing_while_the_run_stops_itself_does_not_hang_it() -> None:
    """The main thread stops a run too (the window's Esc): a stop signal landing while it
    holds the stop event's lock, inside ``set()``, once waited for that lock forever."""
    stop, received = serving.RunStop(), []
    restore = serving._stop_on_signals(stop, lambda: None, received)
    finished = threading.Event()

    def stop_while_signalled() -> None:
        with stop._cond:  # where the main thread is inside stop.set()
            signal.raise_signal(signal.SIGTERM)
            sum(range(1000))  # the handler runs between these bytecodes
        finished.set()

    try:
        stop_while_signalled()
    finally:
        restore()
    assert finished.is_set()
    assert stop.is_set()
    assert received == ["SIGTERM"]


@pytest.mark.usefixtures("ctrl_c")
@pytest.mark.parametrize("first", ["SIGINT", "SIGTERM"])
def test_ctrl_c_stops_a_run_as_sigterm_does_and_raises_nothing(first: str) -> None:
    """Ctrl-C sets the run's stop and wakes its loop, as SIGTERM does, and raises nothing, the
    first time or the next (a sweep's worker gets Ctrl-C from the terminal, then SIGINT from
    the sweep). KeyboardInterrupt, raised where the run happened to be, landed in a step or a
    recording's write (see the recorded-run tests below) and, once the run was stopping, in
    the stopping of the program's process tree, leaving its detached children running."""
    stop, woken, received = serving.RunStop(), [], []
    before = signal.getsignal(signal.SIGINT)
    restore = serving._stop_on_signals(stop, lambda: woken.append(True), received)
    try:
        try:
            signal.raise_signal(getattr(signal, first))
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt:
            pytest.fail("Ctrl-C raised KeyboardInterrupt in the run")
    finally:
        restore()
    assert stop.is_set()
    assert woken == [True, True]
    assert received == [first, "SIGINT"]
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.usefixtures("ctrl_c")
def test_ctrl_c_as_the_program_starts_still_stops_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C landing after the program's process exists, but before the run holds it (the
    program just started, its start-up line being said), still stops it with the run."""
    start = serving._start_program
    started: list[int] = []

    def interrupted(*args: object, **kwargs: object) -> object:
        program = start(*args, **kwargs)  # type: ignore[arg-type]
        started.append(program.process.pid)
        raise KeyboardInterrupt  # before serve has it

    monkeypatch.setattr(serving, "_start_program", interrupted)
    sleeper = tmp_path / "sleeper.py"
    sleeper.write_text("import time\ntime.sleep(300)\n", encoding="utf-8")
    served = run_program(Simulation.from_config(), f"python {sleeper}")
    assert served.ended_by == "quit"
    assert len(started) == 1
    assert started[0] not in descendants()


@pytest.mark.usefixtures("ctrl_c")
def test_ctrl_c_in_the_cleanup_after_an_error_still_stops_the_program(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run that fails (an internal error) stops its program on the way out; Ctrl-C landing
    in that cleanup is only noted, so the program and what it detached still go, and the
    error is what the caller gets."""

    def fails(*_args: object, **_kwargs: object) -> None:
        raise RuntimeError("the loop failed")

    program_stop = Program.stop

    def ctrl_c_first(program: Program, grace: float = 2.0) -> int:
        signal.raise_signal(signal.SIGINT)  # as the cleanup begins to stop the program
        return program_stop(program, grace)

    monkeypatch.setattr(serving.Runner, "run", fails)
    monkeypatch.setattr(Program, "stop", ctrl_c_first)
    detach = tmp_path / "detach.py"
    child = tmp_path / "child"
    detach.write_text(
        "import subprocess, sys, time\n"
        "p = subprocess.Popen(['sleep', '300'], start_new_session=True)\n"
        f"open({str(child)!r}, 'w').write(str(p.pid))\n"
        "time.sleep(300)\n",
        encoding="utf-8",
    )
    before = descendants()
    with pytest.raises(RuntimeError, match="the loop failed"):
        run_program(Simulation.from_config(), f"python {detach}")
    assert descendants() <= before


WHERE_CTRL_C_LANDS = {
    "right after a trace write": (TraceWriter, "_write"),
    "as the events file closes": (EventLog, "close"),
}
"""Where an in-process run meets Ctrl-C: the first time that method runs with something to
write (the trace flushes rows during the run; events.jsonl closes as the recording ends)."""


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")
@pytest.mark.parametrize("where", WHERE_CTRL_C_LANDS)
def test_ctrl_c_landing_in_a_recording_write_leaves_it_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, where: str
) -> None:
    """Ctrl-C raised KeyboardInterrupt wherever the run was: right after the trace's write
    of its pending rows, before it let go of them, the recording's close wrote them again
    (trace.csv ran backwards and its replay differed); and the default handler was back
    before the recording closed, so Ctrl-C there left no report (and a traceback). It now
    only stops the run, and the recording is finished once, in order."""
    cls, name = WHERE_CTRL_C_LANDS[where]
    method = getattr(cls, name)
    landed: list[bool] = []

    def then_ctrl_c(self: object, *args: object) -> object:
        done = method(self, *args)
        if not landed and (name == "close" or args[1]):  # rows written, not the header
            landed.append(True)
            signal.raise_signal(signal.SIGINT)
        return done

    monkeypatch.setattr(cls, name, then_ctrl_c)
    program = tmp_path / "program.py"
    program.write_text(
        "from simmer.client import connect\n"
        "with connect() as robot:\n"
        "    for turn in range(20):\n"
        "        robot.drive('w0', 3 if turn % 2 else -3)\n"
        "        robot.send('u0,u1')\n"
        "        robot.sleep(40)\n",  # 2,400 steps: rows written during the run
        encoding="utf-8",
    )
    folder = tmp_path / "run"
    try:
        run_program(Simulation.from_config(), f"{sys.executable} {program}", record=folder)
    except KeyboardInterrupt:  # not raised out of the test session, which it would end
        pytest.fail("Ctrl-C came out of the run as KeyboardInterrupt")
    assert landed
    _assert_finished(tmp_path, folder, said="")


DETACHING_PROGRAM = """
import subprocess, sys
from pathlib import Path
from simmer.client import connect

here = Path(sys.argv[1])
child = subprocess.Popen(
    ["setsid", "sleep", "300"],
    stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
)
(here / "child.pid").write_text(str(child.pid))
with connect() as robot:
    for turn in range(int(sys.argv[2])):
        robot.drive("w0", 2 if turn % 2 else -2)
        robot.send("u0,u1,u2")
        robot.sleep(1.0)
(here / "exiting").write_text("")
"""
"""A program that leaves a detached child running, drives and reads for a number of turns
(its second argument), then says it is exiting."""


def _recorded_run(tmp_path: Path, turns: int) -> tuple[subprocess.Popen[bytes], Path]:
    """``simmer run --program`` of :data:`DETACHING_PROGRAM`, recorded into tmp_path/run."""
    program = tmp_path / "program.py"
    program.write_text(DETACHING_PROGRAM, encoding="utf-8")
    folder = tmp_path / "run"
    command = [
        sys.executable, "-c", "from simmer.cli import main; main()", "run", "--headless",
        "--port", "0", "--port-rx", "0", "--port-tx", "0", "--record", str(folder),
        "--program", f"{sys.executable} {program} {tmp_path} {turns}",
    ]  # fmt: skip
    with (tmp_path / "out").open("wb") as out:
        process = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT)
    return process, folder


def _event_lines(folder: Path) -> int:
    try:
        return (folder / "events.jsonl").read_bytes().count(b"\n")
    except FileNotFoundError:
        return 0


def _assert_finished(tmp_path: Path, folder: Path, said: str | None = None) -> None:
    """The recording in ``folder`` was finished: its trace in order, its report there, and
    ``simmer replay --check`` finds the re-simulation the same (``said``: what the run said,
    default: tmp_path/out)."""
    if said is None:
        said = (tmp_path / "out").read_text(errors="replace")
    with (folder / "trace.csv").open(encoding="utf-8") as file:
        rows = list(csv.DictReader(file))
    steps = [int(row["step"]) for row in rows]
    assert steps == sorted(set(steps)), f"trace rows out of order; the run said:\n{said}"
    assert (folder / "report.md").is_file(), f"no report.md; the run said:\n{said}"
    result = CliRunner().invoke(app, ["replay", "--check", str(folder)])
    assert result.exit_code == 0, f"{result.output}\nthe run said:\n{said}"
    assert "matches the recording" in result.output


SIGINT_MOMENTS = [
    *(("events", lines) for lines in (0, 1, 2, 3, 4, 6, 8, 11, 15, 20, 26, 33, 41, 50, 62)),
    *(("its exit", turns) for turns in (1, 2, 3, 5, 8, 13, 21, 34)),
]
"""When SIGINT lands: once ``events.jsonl`` holds that many lines (0: once the manifest is
written), or once the program (of that many turns) says it is exiting, as it is stopped."""


def _interrupt_recorded_runs(tmp_path: Path, moments: list[tuple[str, int]]) -> None:
    """SIGINT to a recorded run at each of these ``moments``; each recording finished."""
    before = descendants()
    for number, (moment, count) in enumerate(moments):
        here = tmp_path / str(number)
        here.mkdir()
        process, folder = _recorded_run(here, count if moment == "its exit" else 1000)
        try:
            wait_for(_reached(moment, count, here), f"{moment} {count}", 60)
            process.send_signal(signal.SIGINT)
            assert process.wait(timeout=60) == 0, (here / "out").read_text(errors="replace")
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
        _assert_finished(here, folder)
        child = int((here / "child.pid").read_text()) if (here / "child.pid").exists() else None
        assert child is None or not Path(f"/proc/{child}").exists() or _zombie(child)
    assert descendants() <= before


def _reached(moment: str, count: int, here: Path) -> Callable[[], bool]:
    """Whether the run in ``here`` is at that moment of :data:`SIGINT_MOMENTS`."""
    if moment == "its exit":
        return (here / "exiting").exists
    if count == 0:
        return (here / "run" / "manifest.json").exists
    return lambda: _event_lines(here / "run") >= count


def _zombie(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1].startswith("Z")
    except (OSError, IndexError):
        return True


@pytest.mark.usefixtures("ctrl_c")
@pytest.mark.slow
@pytest.mark.timeout(600)
def test_ctrl_c_at_any_moment_of_a_recorded_program_run_finishes_the_recording(
    tmp_path: Path,
) -> None:
    """SIGINT to ``simmer run --program ... --record`` (a program leaving a detached child) at
    23 moments, from the recording's start to the program's stop: every recording ends with
    its trace rows in order and its report, its replay matches, and no process is left. The
    windows where Ctrl-C broke a recording are narrow (a trace write, the recording's
    close): 46 such SIGINTs to the old code missed them, and the in-process test above puts
    Ctrl-C in each; this one checks every other moment of a real run."""
    _interrupt_recorded_runs(tmp_path, SIGINT_MOMENTS)


@pytest.mark.usefixtures("ctrl_c")
@pytest.mark.slow
@pytest.mark.timeout(600)
def test_ctrl_c_finishes_the_recording_beside_a_busy_cpu(tmp_path: Path, busy_cpu: None) -> None:
    """As above, with another process keeping a CPU busy, at every fourth moment (six, from
    the first events to the program's exit; the test above takes every moment)."""
    _interrupt_recorded_runs(tmp_path, SIGINT_MOMENTS[1::4])
