"""``simmer tap``'s command line: a port that will not open, or a configuration with a
mistake, is one plain line and exit status 1, and nothing is recorded."""

from __future__ import annotations

from pathlib import Path

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
