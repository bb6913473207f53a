"""``simmer tap``'s command line: a port that will not open, or a configuration with a
mistake, is one plain line and exit status 1, and nothing is recorded."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app

from helpers import REPO

CONFIG = REPO / "examples" / "simmer_default.toml"


def test_a_port_that_will_not_open_is_one_line(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        app,
        [
            "tap",
            str(tmp_path / "rfcomm9"),
            "--config",
            str(CONFIG),
            "--record",
            str(tmp_path / "r"),
        ],
    )
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"cannot open the robot's port {tmp_path / 'rfcomm9'}")
    assert "Traceback" not in result.output
    assert not (tmp_path / "r").exists()


def test_a_configuration_mistake_names_its_line(tmp_path: Path) -> None:
    config = tmp_path / "robot.toml"
    config.write_text("protocol = 'framd'\n")
    result = CliRunner().invoke(
        app, ["tap", "tcp://127.0.0.1:1", "--config", str(config), "--record", str(tmp_path / "r")]
    )
    assert result.exit_code == 1
    assert f"{config}:1: protocol" in result.output
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(("command", "doing"), [("plot", "draw"), ("replay", "replay")])
def test_plot_and_replay_point_a_taps_folder_to_compare(
    tmp_path: Path, command: str, doing: str
) -> None:
    from simmer.config import load_config
    from simmer.tap.folder import TapRecorder

    recorder = TapRecorder(tmp_path / "real", load_config(), "/dev/rfcomm0")
    recorder.close(
        "x", False, bytes_sent=0, bytes_received=0, stray=0, program=None, program_status=None
    )
    result = CliRunner().invoke(app, [command, str(tmp_path / "real")])
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1
    assert f"no true pose to {doing}; simmer compare {tmp_path / 'real'}" in lines[0]
