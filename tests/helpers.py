"""Shared helpers for the core tests: small configurations built from the default."""

from __future__ import annotations

import copy
import os
import re
import subprocess
import sys
import threading
import time
import tomllib
import tracemalloc
from collections.abc import Callable
from importlib.resources import files
from pathlib import Path
from typing import Any, TypeVar

import pytest

from simmer import SimConfig, Simulation
from simmer.config import config_from_dict

REPO = Path(__file__).resolve().parent.parent
EXAMPLES = REPO / "examples"
SIMMER_PY = REPO / "tests" / "fixtures" / "simmer_py"
"""Configuration files written in the original SimMeR's style."""
PROJECT = EXAMPLES / "project.toml"
COMMENTED_SETTING = re.compile(r"^# ([A-Za-z_]+ = .*)$", re.MULTILINE)
"""A setting commented out: ``# bias = {...}`` (prose comments have no ``key = ``)."""
SIMMER_PY_FILES = [
    SIMMER_PY / "default_config.py",
    SIMMER_PY / "lab_rover_quiet.py",
    SIMMER_PY / "lab_rover_noisy.py",
    SIMMER_PY / "with_device" / "config.py",
    SIMMER_PY / "tof_device" / "config.py",
]
LAB_SEQUENCE = [
    "w0-36", "r0-90", "w0-36", "r0-90", "w0-12", "r0--90", "w0-24", "r0--90", "w0-6", "r0-720",
]  # fmt: skip


def default_data() -> dict[str, Any]:
    """The built-in default configuration as plain data (a fresh copy to modify)."""
    text = files("simmer").joinpath("data/default.toml").read_text(encoding="utf-8")
    return copy.deepcopy(tomllib.loads(text))


def noisy_data() -> dict[str, Any]:
    """The default rover with the lab's noise: sensor error, drive error and a curving bias."""
    data = default_data()
    for sensor in data["sensors"].values():
        sensor["error"] = 0.05
    data["drives"]["w0"]["error"] = {"x": 0.02, "y": 0.05, "rotation": 1}
    data["drives"]["w0"]["bias"] = {"rotation": 0.2}
    data["drives"]["r0"]["error"] = {"x": 0.003, "y": 0.003, "rotation": 0.02}
    return data


def make_config(data: dict[str, Any]) -> SimConfig:
    """Validate configuration data."""
    return config_from_dict(data, "<test>", REPO)


def noisy_config() -> SimConfig:
    """:func:`noisy_data`, validated."""
    return make_config(noisy_data())


def drive_noisily(sim: Simulation, reset: bool = True) -> None:
    """Every kind of input: commands with reads, a bad command, held keys, a drag, a collision
    and (optionally) a reset followed by a turn."""
    for message in LAB_SEQUENCE[:4]:
        sim.command("u0,u1,u2,u3", client="test")
        sim.command(message)
        while sim.robot.any_drive_moving:
            sim.step()
            if sim.steps % 7 == 0:
                sim.command("u0,w0-0,u9")  # u9: no such device, NaN
    sim.set_manual_keys("wd")
    sim.step(40)
    sim.set_manual_keys("")
    assert sim.place_robot(6.0, 30.0, 90.0)
    sim.command("w0-30,u1")  # into a wall: a collision, then out of it
    sim.step(400)
    sim.command("w0--6")
    sim.step(100)
    if reset:
        sim.reset()
        sim.command("r0-45,u0")
        sim.step(50)


def make_sim(data: dict[str, Any] | None = None, seed: int | None = None) -> Simulation:
    """A simulation of ``data`` (default: the built-in default)."""
    return Simulation(make_config(data if data is not None else default_data()), seed=seed)


def run_sequence(sim: Simulation, sequence: list[str]) -> None:
    """Send each command, check it was accepted, and wait until the drives are idle."""
    for message in sequence:
        assert sim.command(message) == [float("inf")], message
        assert sim.run_until_idle(max_seconds=60)


DEADLINE = 20.0
"""Seconds any wait for an event may take before the test fails (far beyond what it needs: the
machine is shared, and a test never asserts on how long something took)."""
POLL = 0.005
"""Seconds between two looks at a condition :func:`wait_for` polls."""


def wait_for(condition: Callable[[], object], what: str, deadline: float = DEADLINE) -> None:
    """Poll ``condition`` until it is true; fail naming ``what`` after ``deadline`` s. The one
    way a test waits for something another thread or process does."""
    end = time.monotonic() + deadline
    while not condition():
        if time.monotonic() > end:
            pytest.fail(f"still waiting for {what} after {deadline:g} s")
        let_time_pass(POLL)


def let_time_pass(seconds: float) -> None:
    """Let ``seconds`` of wall time go by where the behaviour under test is about time passing
    (a server's back-off); never to wait for a result, and never before an assertion on how
    long something took."""
    threading.Event().wait(seconds)  # never set: the wait is the pause


def uncomment(text: str, line: str) -> str:
    """``text`` with the commented-out ``line`` (``bias = ...``) made a setting."""
    return text.replace(f"# {line}", line, 1)


def project_data(**scenario: str) -> dict[str, Any]:
    """examples/project.toml as data, with scenario settings replaced."""
    data = tomllib.loads(PROJECT.read_text(encoding="utf-8"))
    data = copy.deepcopy(data)
    data["scenario"].update(scenario)
    return data


def project_sim(seed: int = 1, **scenario: str) -> Simulation:
    """A simulation of examples/project.toml with scenario settings replaced."""
    return Simulation(make_config(project_data(**scenario)), seed=seed)


T = TypeVar("T")


def peak_memory(call: Callable[[], T]) -> tuple[T, int]:
    """``call()``'s result and the most memory (bytes) Python allocated at once while it ran:
    a bound on the work done that, unlike its time, is the same on a busy machine or a quiet
    one (a file read whole or a grid of runs built shows; how long it took: benchmarks/)."""
    tracemalloc.start()
    try:
        result = call()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return result, peak


FREE_PORTS = ["--port", "0", "--port-rx", "0", "--port-tx", "0"]
"""``simmer run`` on ports the system picks, so tests never meet another simulator."""


def run_simmer(
    *args: str | Path, cwd: Path | None = None, timeout: float = 240
) -> subprocess.CompletedProcess[str]:
    """``simmer ARGS`` as a process of its own, without a display; its output as UTF-8 text
    (bytes that are not UTF-8 kept as escapes, so a test can still read them)."""
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    return subprocess.run(
        [sys.executable, "-m", "simmer", *map(str, args)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        encoding="utf-8",
        errors="backslashreplace",
        timeout=timeout,
        check=False,
    )
