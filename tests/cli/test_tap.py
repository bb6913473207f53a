"""``simmer tap``'s command line: a port that will not open, or a configuration with a
mistake, is one plain line and exit status 1, and nothing is recorded."""

from __future__ import annotations

import math
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


def _tap_folder(folder: Path) -> None:
    """A tap's run folder as the tap writes one: a move, polls while it moves, one it
    refused, reads of two sensors, a read the robot never answered."""
    from simmer.config import load_config
    from simmer.tap.decode import Exchange
    from simmer.tap.folder import TapRecorder

    recorder = TapRecorder(folder, load_config(), "/dev/rfcomm0")
    start = recorder.start
    for at, message, replies in [
        (0.5, "u0,u1", [4.2, 3.1]),
        (1.0, "w0-6", [math.inf]),
        (1.1, "w0-0", [math.nan]),
        (1.2, "w0-0", [math.nan]),
        (1.3, "w0-3", [math.nan]),
        (2.0, "w0-0", [math.inf]),
        (2.1, "u0,u1", [10.3, 3.0]),
        (2.2, "u0", [math.nan]),
    ]:
        recorder.record(Exchange(message, len(replies), start + at, replies, start + at + 0.02))
    recorder.close(
        "program", False, bytes_sent=60, bytes_received=40, stray=0, program=None,
        program_status=0,
    )  # fmt: skip


def test_plot_draws_a_taps_folder_as_its_traffic_over_time(tmp_path: Path) -> None:
    from simmer.tap.folder import load_tap_run
    from simmer.tap.timeline import TIMELINE_IMAGE, traffic

    folder = tmp_path / "real"
    _tap_folder(folder)
    seen = traffic(load_tap_run(folder))
    assert [v for _, v, _ in seen.drives["w0"]] == [6.0, 0.0, 0.0, 3.0, 0.0]
    assert [t for t, _, r in seen.drives["w0"] if math.isnan(r)] == pytest.approx(
        [1.1, 1.2, 1.3], abs=1e-3
    )
    assert [v for _, v in seen.readings["u0"]] == pytest.approx([4.2, 10.3])
    assert seen.unanswered == pytest.approx([2.2], abs=1e-3)
    result = CliRunner().invoke(app, ["plot", str(folder)])
    assert result.exit_code == 0, result.output
    lines = result.output.strip().splitlines()
    assert lines[0].startswith(f"{folder} is a tap's run of the real robot: no true pose")
    assert lines[-1] == f"wrote {folder / TIMELINE_IMAGE}"
    picture = (folder / TIMELINE_IMAGE).read_bytes()
    assert picture[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (folder / "path.png").exists()


def test_replay_of_a_taps_folder_is_one_line_pointing_to_plot(tmp_path: Path) -> None:
    _tap_folder(tmp_path / "real")
    result = CliRunner().invoke(app, ["replay", str(tmp_path / "real")])
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1
    assert f"no pose to replay; simmer plot {tmp_path / 'real'} draws its commands" in lines[0]
