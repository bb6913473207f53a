"""``serve``: stop signals end a run cleanly, wherever they land."""

from __future__ import annotations

import os
import signal
import threading
from pathlib import Path

import pytest

from link_support import launch, output, run_program, stop
from simmer import serve as serving
from simmer.lockstep import Program
from simmer.proctree import descendants
from simmer.world import Simulation

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
    restore = serving._stop_on_signals(
        stop, lambda: woken.append(True), received, running=lambda: True
    )
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
    restore = serving._stop_on_signals(stop, lambda: None, received, running=lambda: True)
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
@pytest.mark.parametrize("first", ["SIGINT", "SIGTERM", "its end"])
def test_ctrl_c_once_a_run_is_stopping_is_only_noted(first: str) -> None:
    """Ctrl-C raises KeyboardInterrupt while the run goes on; once it is stopping (a first
    Ctrl-C, a stop signal, or its program's exit or a limit) another is only noted: raised,
    it landed in the stopping of the program's process tree (a sweep's worker gets Ctrl-C
    from the terminal, then SIGINT from the sweep) and left its detached children running."""
    stop, received, ended = serving.RunStop(), [], []
    before = signal.getsignal(signal.SIGINT)
    restore = serving._stop_on_signals(stop, lambda: None, received, running=lambda: not ended)
    try:
        if first == "SIGINT":
            with pytest.raises(KeyboardInterrupt):
                signal.raise_signal(signal.SIGINT)
        elif first == "SIGTERM":
            signal.raise_signal(signal.SIGTERM)
        else:
            ended.append("program")
        try:
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt:
            pytest.fail("Ctrl-C raised KeyboardInterrupt while the run was stopping")
    finally:
        restore()
    noted = [] if first == "its end" else [first]
    assert received == [*noted, "SIGINT"]
    assert signal.getsignal(signal.SIGINT) is before


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
