"""Plots of a run folder (issue 11, item 3): path.png and sensors.png are real PNGs whose pixels
show the path where the trace says the robot was; ``simmer plot DIR`` writes and names them."""

from __future__ import annotations

import csv
import json
import math
import os
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from simmer.cli import app
from simmer.config import load_config
from simmer.errors import PlotError
from simmer.record.plots import (
    MAX_REPORT_BYTES,
    PATH_COLOR,
    plot_run,
    read_run,
    sensor_panels,
    write_path_plot,
)

RATE = 60.0
SPEED = 6.0  # inches a second
SENSORS = ("u0", "u1", "u2", "u3")


def drive(start: tuple[float, float], end: tuple[float, float]) -> list[tuple[float, float]]:
    """Positions at RATE samples a second from start to end at SPEED."""
    steps = max(1, round(math.dist(start, end) / SPEED * RATE))
    return [
        (start[0] + (end[0] - start[0]) * i / steps, start[1] + (end[1] - start[1]) * i / steps)
        for i in range(1, steps + 1)
    ]


def lab_path() -> list[tuple[float, float, float]]:
    """(x, y, heading): from the start (6, 42) up to (6, 6), a turn, then right to (30, 6)."""
    up = [(x, y, 180.0) for x, y in drive((6.0, 42.0), (6.0, 6.0))]
    turn = [(6.0, 6.0, 180.0 + 90.0 * i / 30) for i in range(1, 31)]
    right = [(x, y, 270.0) for x, y in drive((6.0, 6.0), (30.0, 6.0))]
    return [(6.0, 42.0, 180.0), *up, *turn, *right]


def write_run(
    folder: Path, poses: list[tuple[float, float, float]], reset_at: int | None = None
) -> None:
    """A run folder: manifest of the default configuration, trace of ``poses`` (the clock back
    to 0 at sample ``reset_at``), a few events."""
    folder.mkdir(parents=True, exist_ok=True)
    config = load_config()
    devices = [{"id": d.id, "group": d.group, "kind": d.kind, "x": 1} for d in config.devices]
    settings = {**config.settings.model_dump(mode="json"), "added_later": True}
    manifest = {
        "simmer_version": "test",
        "config": {"source": "/labs/lab1_rover.toml", "settings": settings, "devices": devices},
        "seed": 5489,
    }
    (folder / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    with (folder / "trace.csv").open("w", newline="", encoding="utf-8") as file:
        writer = csv.writer(file)
        writer.writerow(["time", "step", "x", "y", "heading", "collisions", *SENSORS])
        for i, (x, y, heading) in enumerate(poses):
            step = i - reset_at if reset_at is not None and i >= reset_at else i
            readings = ["" if step < 10 else f"{y - 3.0 + k:.3f}" for k in range(len(SENSORS))]
            collisions = int(i >= len(poses) - 1)
            writer.writerow([step / RATE, step, x, y, heading, collisions, *readings])
    end = (len(poses) - 1) / RATE
    events: list[dict[str, object]] = [
        {"type": "run", "time": 0.0, "step": 0, "what": "program-start"},
        {"type": "command", "time": 0.0, "step": 0, "message": "w0-36", "replies": [1.0]},
        {"type": "command", "time": 1.0, "step": 60, "message": "u0", "replies": [30.0]},
        {"type": "command", "time": 3.0, "step": 180, "message": "zz", "replies": ["nan"]},
        {"type": "command", "time": 6.5, "step": 390, "message": "r0-90", "replies": [1.0]},
        {"type": "command", "time": 8.0, "step": 480, "message": "w0-24,u1", "replies": [1, "inf"]},
        {"type": "collision", "time": end, "step": len(poses) - 1, "pose": [30.0, 6.0, 270.0]},
        {"type": "reached", "time": end, "step": len(poses) - 1, "task2_time": end, "x": 1},
        {"type": "something new", "time": 1.0},
    ]
    lines = [json.dumps(event) for event in events]
    lines.append('{"type": "command", "time": 9.9, "mess')  # a run killed mid-line
    (folder / "events.jsonl").write_text("\n".join(lines), encoding="utf-8")


def path_pixels(image: Image.Image) -> np.ndarray:
    """True where a pixel is the path's colour."""
    rgb = np.asarray(image.convert("RGB"), dtype=np.int32)
    want = np.array([int(PATH_COLOR[i : i + 2], 16) for i in (1, 3, 5)])
    return np.abs(rgb - want).sum(axis=2) < 40


@pytest.mark.slow
def test_path_plot_shows_the_path_where_the_trace_says(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    poses = lab_path()
    write_run(folder, poses)
    run = read_run(folder)
    assert [c.message for c in run.commands] == ["w0-36", "u0", "zz", "r0-90", "w0-24,u1"]
    assert [c.nan for c in run.commands] == [False, False, True, False, False]
    assert math.isinf(run.commands[4].replies[1])
    assert run.collisions[0].pose == (30.0, 6.0)
    assert list(run.trace.sensors) == list(SENSORS)
    assert (run.seed, run.source, run.kinds["u2"]) == (5489, "/labs/lab1_rover.toml", "ultrasonic")
    assert math.isnan(run.trace.sensors["u0"][0])
    assert run.trace.length() == pytest.approx(36.0 + 24.0)

    pixels = write_path_plot(run, folder / "path.png")
    with Image.open(folder / "path.png") as image:
        assert image.format == "PNG"
        assert image.size > (800, 400)
        path = path_pixels(image)
    near = 0
    for x, y, _ in poses[::15]:
        col, row = pixels.pixel(x, y)
        window = path[round(row) - 6 : round(row) + 7, round(col) - 6 : round(col) + 7]
        near += bool(window.any())
    assert near >= 0.9 * len(poses[::15])  # markers (start, commands, end) cover a few
    # The open cell at x 12..24, y 12..24 is 6 inches or more from the path: none of its colour.
    (c0, r0), (c1, r1) = pixels.pixel(13.0, 13.0), pixels.pixel(23.0, 23.0)
    assert min(c1 - c0, r1 - r0) > 50  # +y is down the page
    assert not path[round(r0) : round(r1), round(c0) : round(c1)].any()


@pytest.mark.slow
def test_plot_run_writes_both_pngs_and_links_them_from_the_report(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    write_run(folder, lab_path())
    (folder / "report.md").write_text("# Run\n\nReached the block.\n", encoding="utf-8")
    written = plot_run(folder)
    assert written == [folder / "path.png", folder / "sensors.png", folder / "report.md"]
    for path in written[:2]:
        with Image.open(path) as image:
            assert image.format == "PNG"
            assert min(image.size) > 300
            colours = image.convert("RGB").getcolors(maxcolors=1 << 20)
            assert len(colours or []) > 20  # drawn, not a blank page
    report = (folder / "report.md").read_text(encoding="utf-8")
    assert report.startswith("# Run\n\nReached the block.\n")
    assert report.count("## Plots") == 1
    assert report.endswith(
        "\n## Plots\n\n![The robot's true path](path.png)\n\n"
        "![Sensor readings against time](sensors.png)\n"
    )
    assert plot_run(folder) == written[:2]
    assert (folder / "report.md").read_text(encoding="utf-8") == report  # linked once


@pytest.mark.slow
def test_a_report_that_already_shows_the_plots_is_left_alone(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    write_run(folder, lab_path())
    text = "# Run\n\n![The path](path.png)\n\n![Sensors](sensors.png)\n"
    (folder / "report.md").write_text(text, encoding="utf-8")
    assert len(plot_run(folder)) == 2
    assert (folder / "report.md").read_text(encoding="utf-8") == text


def test_a_report_larger_than_any_is_not_read_whole(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    write_run(folder, lab_path())
    big = b"# Run\n" + b"x" * MAX_REPORT_BYTES
    (folder / "report.md").write_bytes(big)
    with pytest.raises(PlotError, match=r"but not report\.md: .*MAX_REPORT_BYTES"):
        plot_run(folder)
    assert (folder / "report.md").read_bytes() == big
    assert (folder / "path.png").is_file()


def test_sensor_panels_group_by_kind_or_else_by_id_prefix(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    write_run(folder, lab_path())
    run = read_run(folder)
    assert sensor_panels(run) == [("ultrasonic: distance (in)", list(SENSORS))]
    run.kinds = {"u0": "compass", "u1": "my_lidar"}
    assert sensor_panels(run) == [
        ("compass: heading (°)", ["u0"]),
        ("my_lidar: reading", ["u1"]),
        ("u…: reading", ["u2", "u3"]),
    ]


@pytest.mark.slow
def test_a_reset_starts_a_new_part_of_the_run(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    first = [(6.0, 42.0 - i * 0.1, 180.0) for i in range(120)]
    write_run(folder, first + first, reset_at=len(first))
    with (folder / "events.jsonl").open("a", encoding="utf-8") as file:
        file.write("\n" + json.dumps({"type": "reset", "time": 2.0, "step": 120}))
        file.write("\n" + json.dumps({"type": "command", "time": 1.0, "message": "u0"}))
    run = read_run(folder)
    assert run.trace.parts == 2
    assert run.trace.offsets().tolist() == pytest.approx([0.0, 119 / RATE])
    assert run.commands[-1].part == 1
    assert run.trace.length() == pytest.approx(2 * 11.9)  # no jump back to the start counted
    assert len(plot_run(folder)) == 2


@pytest.mark.slow
def test_simmer_plot_names_the_files(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    write_run(folder, lab_path())
    result = CliRunner().invoke(app, ["plot", str(folder)])
    assert result.exit_code == 0, result.output
    assert str(folder / "path.png") in result.output
    assert str(folder / "sensors.png") in result.output
    assert (folder / "path.png").stat().st_size > 10_000


def test_simmer_plot_without_a_trace_says_so_in_one_line(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["plot", str(tmp_path)])
    assert result.exit_code == 1
    assert result.output.strip() == (
        f"no trace.csv in {tmp_path}: not a run folder (record one with simmer run --record)"
    )
    assert not (tmp_path / "path.png").exists()


def test_unreadable_folders_raise_plot_errors(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    write_run(folder, lab_path())
    (folder / "manifest.json").unlink()
    with pytest.raises(PlotError, match=r"no manifest\.json"):
        read_run(folder)
    (folder / "manifest.json").write_text('{"config": {"settings": {"walls": 3}}}', "utf-8")
    with pytest.raises(PlotError, match="setting walls"):
        read_run(folder)
    (folder / "trace.csv").write_text("time,x,y\n0,1,2\n", encoding="utf-8")
    with pytest.raises(PlotError, match="no column heading"):
        read_run(folder)
    (folder / "trace.csv").write_text("time,x,y,heading\n", encoding="utf-8")
    with pytest.raises(PlotError, match="no rows"):
        read_run(folder)


def test_hostile_names_in_a_run_folder_are_drawn_as_text(tmp_path: Path) -> None:
    """A folder's name (not UTF-8 on disk: a lone surrogate in Python), the configuration's
    name and the sensors' names are drawn in the titles and legends; a lone surrogate stopped
    matplotlib and a ``$`` pair was parsed as mathematics (``\\foo``: a traceback)."""
    folder = tmp_path / os.fsdecode(b"run\xff")
    write_run(folder, lab_path())
    manifest = json.loads((folder / "manifest.json").read_text(encoding="utf-8"))
    manifest["config"]["source"] = "/labs/\ud800 $\\foo$ \u202e\x00.toml"
    (folder / "manifest.json").write_text(json.dumps(manifest), encoding="utf-8")
    trace = (folder / "trace.csv").read_text(encoding="utf-8")
    header, rest = trace.split("\n", 1)
    hostile = header.replace("u1", "u1$\\foo$").replace("u2", "u2\u202e\ufeff\u200b")
    (folder / "trace.csv").write_text(f"{hostile}\n{rest}", encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "Glyph missing from font" is a warning
        written = plot_run(folder)
    assert written == [folder / "path.png", folder / "sensors.png"]
    for path in written:
        with Image.open(path) as image:
            assert image.format == "PNG"
