"""Ports set once: ``simmer run --ports auto`` prints the three it took and how to give them to
other terminals; with ``SIMMER_PORTS`` set so, ``simmer console``, the client library's examples
and a raw-socket example (the original's style) all reach that simulator, not SimMeR's own
ports. Real processes on loopback."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from helpers import EXAMPLES, run_simmer, wait_for

EXPORT = re.compile(r"other terminals: export SIMMER_PORTS=(\d+),(\d+),(\d+)")


class Simulator:
    """``simmer run --headless`` with ``args``, its printout collected line by line."""

    def __init__(self, *args: str, env: dict[str, str] | None = None) -> None:
        self.lines: list[str] = []
        self.process = subprocess.Popen(
            [sys.executable, "-m", "simmer", "run", "--headless", "--seconds", "600", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env={**os.environ, "SDL_VIDEODRIVER": "dummy", **(env or {})},
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))

    def said(self, pattern: re.Pattern[str]) -> re.Match[str] | None:
        return next(filter(None, map(pattern.search, list(self.lines))), None)

    def stop(self) -> None:
        self.process.terminate()
        self.process.wait(timeout=60)
        self._reader.join(timeout=60)
        assert self.process.stdout is not None
        self.process.stdout.close()


def _python(script: Path, env: dict[str, str], stdin: str = "") -> str:
    done = subprocess.run(
        [sys.executable, str(script)],
        input=stdin,
        capture_output=True,
        text=True,
        env={**os.environ, **env},
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


@pytest.mark.slow
def test_ports_auto_are_printed_and_every_client_follows_the_one_variable() -> None:
    simulator = Simulator("--ports", "auto")
    try:
        wait_for(lambda: simulator.said(EXPORT) or simulator.process.poll() is not None,
                 "the simulator's ports")  # fmt: skip
        found = simulator.said(EXPORT)
        assert found is not None, "\n".join(simulator.lines)
        ports = [int(port) for port in found.groups()]
        assert tuple(ports) != (61200, 61201, 61202)
        assert len(set(ports)) == 3
        env = {"SIMMER_PORTS": ",".join(map(str, ports))}
        for name in ("SIMMER_PORT", "SIMMER_PORT_RX", "SIMMER_PORT_TX"):
            env[name] = ""  # only the one variable says where
        readings = _python(EXAMPLES / "simmer_v1_client.py", env, stdin="u0\n\n")
        assert re.search(r"u0 -> \[\d+\.\d+\]", readings), readings
        printed = _python(EXAMPLES / "obstacle_avoidance.py", env)
        assert printed.startswith("step   0"), printed
        assert "obstacle" in printed, printed
        console = subprocess.run(
            [sys.executable, "-m", "simmer", "console", "--ports", env["SIMMER_PORTS"]],
            input="u0\nquit\n", capture_output=True, text=True, timeout=120, check=False,
        )  # fmt: skip
        assert console.returncode == 0, console.stdout + console.stderr
        assert re.search(r"\d+\.\d+", console.stdout), console.stdout
    finally:
        simulator.stop()


@pytest.mark.slow
def test_a_wrong_variable_is_one_line_naming_it_and_check_names_all_three_ports() -> None:
    bad = subprocess.run(
        [sys.executable, "-m", "simmer", "run", "--headless", "--seconds", "1"],
        capture_output=True, text=True, timeout=120, check=False,
        env={**os.environ, "SDL_VIDEODRIVER": "dummy", "SIMMER_PORTS": "62000,62001"},
    )  # fmt: skip
    assert bad.returncode != 0
    assert "SIMMER_PORTS='62000,62001'" in bad.stderr
    assert "Traceback" not in bad.stderr
    checked = run_simmer("check", EXAMPLES / "lab1_rover.toml")
    assert checked.returncode == 0, checked.stderr
    said = " ".join(checked.stdout.split())
    assert "61200 (two-port messages), 61201 (two-port replies) and 61202" in said
    assert "SIMMER_PORTS=62000" in said
    assert "--ports auto" in said
