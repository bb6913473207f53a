"""``simmer run``: what it says when it starts, the ports it serves, and its refusals."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from typer.testing import CliRunner

from link_support import free_port
from simmer.cli import app
from simmer.config import load_config, summarize, with_overrides

from helpers import EXAMPLES


def test_the_start_up_summary_shows_the_ports_in_use() -> None:
    rx, tx, stream = free_port(), free_port(), free_port()
    result = CliRunner().invoke(
        app,
        ["run", "--headless", "--speed", "max", "--seconds", "0.05",
         "--port-rx", str(rx), "--port-tx", str(tx), "--port", str(stream)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert f"127.0.0.1 rx {rx}, tx {tx}" in result.output
    assert f"port {stream}" in result.output
    assert "61200" not in result.output


def test_an_ipv6_host_is_not_blamed_on_another_simmer() -> None:
    result = CliRunner().invoke(
        app,
        ["run", "--headless", "--seconds", "0.05", "--host", "::", "--port-rx", "0",
         "--port-tx", "0", "--port", "0"],
    )  # fmt: skip
    assert result.exit_code == 1
    assert "another simmer" not in result.output
    assert "cannot serve on '::'" in result.output
    assert "IPv4" in result.output


def test_a_port_in_use_may_be_another_simmer() -> None:
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        result = CliRunner().invoke(
            app,
            ["run", "--headless", "--seconds", "0.05", "--port-rx", str(port),
             "--port-tx", "0", "--port", "0"],
        )  # fmt: skip
    assert result.exit_code == 1
    assert "Another simmer run (or another program) is using this port" in result.output


PORTS = ["--port", "0", "--port-rx", "0", "--port-tx", "0"]


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
    fresh = with_overrides(loaded, {"rand_error": True})
    assert "fresh each run (this run's: seed 12)." in summarize(fresh, seed=12)
    drawn = with_overrides(quiet, {"rand_bias": True})
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


@pytest.mark.slow
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


@pytest.mark.slow
def test_cli_refuses_a_serial_link_path_that_exists(tmp_path: Path) -> None:
    path = tmp_path / "robot"
    path.symlink_to("/dev/null")
    result = subprocess.run(
        [sys.executable, "-m", "simmer", "run", "--headless", "--seconds", "0.1", "--port", "0",
         "--port-rx", "0", "--port-tx", "0", "--serial-link", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )  # fmt: skip
    assert result.returncode == 1
    assert "already there" in result.stderr
    assert os.readlink(path) == "/dev/null"


@pytest.mark.parametrize("warns", [False, True])
def test_a_program_run_log_follows_no_planted_link_and_is_kept_only_if_it_warns(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, warns: bool
) -> None:
    """The simulator's log of a ``--program`` run was ``simmer-PID.log`` in the temp folder: a
    link planted at that name was followed (overwriting what it pointed at), and one file was
    left per run. It is now a new file of an unknown name, removed at the end of the run
    unless it holds a warning, and then the last line says where it is."""
    temp = tmp_path / "tmp"
    temp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    victim = tmp_path / "victim.txt"
    victim.write_text("not the simulator's", encoding="utf-8")
    planted = temp / f"simmer-{os.getpid()}.log"
    planted.symlink_to(victim)
    program = tmp_path / "program.py"
    message = "zz9" if warns else "u0"  # an unknown command is logged as a warning
    program.write_text(
        f"from simmer.client import connect\nconnect().send({message!r})\n", encoding="utf-8"
    )
    result = CliRunner().invoke(
        app, ["run", "--headless", *PORTS, "--program", f"{sys.executable} {program}"]
    )
    assert result.exit_code == 0, result.output
    assert victim.read_text(encoding="utf-8") == "not the simulator's"
    left = sorted(path for path in temp.iterdir() if path != planted)
    last = result.output.strip().splitlines()[-1]
    if warns:
        assert len(left) == 1
        assert not left[0].is_symlink()
        assert last.endswith(f"the simulator's log has warnings: {left[0]}")
        assert "zz9" in left[0].read_text(encoding="utf-8")
    else:
        assert left == []
        assert last.endswith("the simulator's log had no warnings and is removed")
