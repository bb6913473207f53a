"""A LiDAR's scans recorded beside the trace (issue 32): every whole scan as the device made
it, replayed byte for byte, bounded, read back only through the reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from simmer import Simulation
from simmer.devices.lidar import Lidar
from simmer.errors import RunFolderError
from simmer.record import RunRecorder
from simmer.record.reader import read_scans
from simmer.record.runfolder import retrace
from simmer.record.scans import ScanWriter

from helpers import default_data, make_config

SCANS = "scans.csv"


def lidar_sim(seed: int = 5, beams: int = 90) -> Simulation:
    """The default rover with a noisy LiDAR ``l0`` of ``beams`` beams at its centre."""
    data = default_data()
    data["sensors"]["l0"] = {"type": "lidar", "position": [0, 0], "beams": beams}
    return Simulation(make_config(data), seed=seed)


def drive(sim: Simulation) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Drive and turn (a skewed scan), and read a beam now and then; the scans the device
    made, as (number, distances, points) after each new one."""
    device = sim.robot.devices["l0"]
    assert isinstance(device, Lidar)
    made = []
    for message in ("w0-6", "r0-120", "w0--4", "r0--45"):
        sim.command(message)
        for _ in range(400):
            number = device.number
            sim.step()
            if device.number != number:
                made.append((device.number, device.distances.copy(), device.points.copy()))
            if sim.steps % 37 == 0:
                sim.command("l0-90,u0")
    return made


def test_every_scan_is_recorded_as_the_device_made_it(tmp_path: Path) -> None:
    sim = lidar_sim()
    with RunRecorder(sim, tmp_path / "run") as recorder:
        made = drive(sim)
    scans = read_scans(tmp_path / "run" / SCANS)
    assert recorder.scans is not None
    assert recorder.scans.scans == len(scans)
    assert [s.number for s in scans] == list(range(1, len(scans) + 1))
    assert len(scans) >= len(made) > 20  # 1,600 steps of 1/60 s at 5.5 scans a second
    by_number = {s.number: s for s in scans}
    dropped = 0
    for number, distances, points in made:
        scan = by_number[number]
        assert scan.device == "l0"
        assert len(scan.distances) == 90
        assert np.allclose(scan.distances, distances, atol=5e-4, rtol=0)
        assert np.allclose(scan.x, points[:, 0], atol=5e-4, rtol=0, equal_nan=True)
        assert np.allclose(scan.y, points[:, 1], atol=5e-4, rtol=0, equal_nan=True)
        dropped += int((scan.distances == 0).sum())
        assert np.array_equal(np.isnan(scan.x), scan.distances == 0)
    assert dropped > 0  # the default 1% dropouts: no return reads 0 and has no point
    assert np.allclose(scans[0].angles[:3], [0.0, 4.0, 8.0])
    times = [s.time for s in scans]
    assert np.allclose(np.diff(times), 1 / 5.5, atol=1e-6)


def test_a_replay_writes_the_same_scans_byte_for_byte(tmp_path: Path) -> None:
    sim = lidar_sim(seed=11)
    with RunRecorder(sim, tmp_path / "run"):
        drive(sim)
        sim.reset()
        sim.command("r0-200")
        sim.step(300)
    result = retrace(tmp_path / "run", tmp_path / "trace.csv", tmp_path / SCANS)
    assert result.differences == []
    recorded = (tmp_path / "run" / SCANS).read_bytes()
    assert (tmp_path / SCANS).read_bytes() == recorded
    numbers = [s.number for s in read_scans(tmp_path / SCANS)]
    assert numbers.count(1) == 2  # the reset: the scans count from 1 again
    other = lidar_sim(seed=12)
    with RunRecorder(other, tmp_path / "other"):
        drive(other)
    assert (tmp_path / "other" / SCANS).read_bytes() != recorded  # the noise is in the scans


def test_a_rover_without_a_lidar_has_no_scans_file(tmp_path: Path) -> None:
    sim = Simulation(make_config(default_data()), seed=1)
    with RunRecorder(sim, tmp_path / "run") as recorder:
        sim.command("w0-3")
        sim.step(100)
    assert recorder.scans is None
    assert not (tmp_path / "run" / SCANS).exists()


def test_the_scans_stop_at_their_limit_at_a_whole_row(tmp_path: Path) -> None:
    sim = lidar_sim(beams=360)
    said: list[str] = []
    writer = ScanWriter(tmp_path / SCANS, sim, max_bytes=40_000, on_stop=said.append)
    sim.add_observer(writer)
    sim.command("r0-360")
    sim.step(600)
    writer.close()
    assert writer.stopped is not None
    assert "MAX_SCAN_BYTES" in writer.stopped
    assert said == [f"{SCANS} stopped: {writer.stopped}"]
    scans = read_scans(tmp_path / SCANS)
    assert 1 <= len(scans) == writer.scans < 10
    assert (tmp_path / SCANS).stat().st_size <= 40_000


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("time,step\n", "line 1: not a scans file's header"),
        ("time,step,device,scan,distances,x,y\n1,2,l0,1,1 2,3 4\n", "line 2: not a scan: 6 cells"),
        ("time,step,device,scan,distances,x,y\n1,2,l0,1,1 2,3 4,5\n", "line 2: not a scan"),
        ("time,step,device,scan,distances,x,y\n1,2,l0,x,1,3,5\n", "line 2: not a scan"),
        ("time,step,device,scan,distances,x,y\n1,2,a b,1,1,3,5\n", "line 2: not a scan"),
        ("time,step,device,scan,distances,x,y\n\xff\n", "cannot read"),
    ],
)
def test_a_broken_scans_file_is_one_line_naming_it(tmp_path: Path, text: str, said: str) -> None:
    path = tmp_path / SCANS
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(RunFolderError, match=said) as caught:
        read_scans(path)
    assert str(path) in str(caught.value)
    assert "\n" not in str(caught.value)


def test_a_last_row_cut_short_is_left_out(tmp_path: Path) -> None:
    path = tmp_path / SCANS
    path.write_text("time,step,device,scan,distances,x,y\n0.5,30,l0,1,1 0,2 nan,3 nan\n0.6,3")
    (scan,) = read_scans(path)
    assert scan.distances.tolist() == [1.0, 0.0]
    assert np.isnan(scan.x[1])


def test_a_scans_file_larger_than_a_recording_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / SCANS
    with path.open("wb") as file:
        file.truncate(64 * 1024 * 1024 + 1)
    with pytest.raises(RunFolderError, match="MAX_SCAN_BYTES"):
        read_scans(path)


# ----------------------------------------------------------------------------- plots


def magenta_pixels(path: Path) -> int:
    """Pixels of a PNG in the scan points' colour (the window's, 220, 0, 220)."""
    from matplotlib.image import imread

    rgb = (imread(path)[:, :, :3] * 255).round().astype(int)
    return int(np.all(np.abs(rgb - (220, 0, 220)) <= 8, axis=2).sum())


@pytest.mark.slow
def test_simmer_plot_draws_every_scan_and_the_scan_at_a_time(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from simmer.cli import app
    from simmer.record.plots import read_run, recorded_scans, scan_at

    folder = tmp_path / "run"
    sim = lidar_sim(seed=2)
    with RunRecorder(sim, folder):
        drive(sim)
    result = CliRunner().invoke(app, ["plot", str(folder), "--scan-at", "2.5"])
    assert result.exit_code == 0, result.output
    for name in ("scans.png", "scan.png"):
        assert f"wrote {folder / name}" in result.output.replace("\n", "")
        assert (folder / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"]({name})" in (folder / "report.md").read_text()
    assert magenta_pixels(folder / "scan.png") > 200  # the points, over the maze and as read

    run = read_run(folder)
    timed = recorded_scans(run)
    at, scan = scan_at(timed, 2.5)
    later = [t for t, s in timed if s.number == scan.number + 1]
    assert at <= 2.5 < later[0]
    assert scan.number == 1 + int(2.5 * 5.5 + 1e-9)  # one at the start, then one a revolution

    early = CliRunner().invoke(app, ["plot", str(folder), "--scan-at", "0"])
    assert early.exit_code == 0  # the scan made at the start pose ended at 0 s
    empty = tmp_path / "none"
    plain = Simulation(make_config(default_data()), seed=1)
    with RunRecorder(plain, empty):
        plain.step(10)
    refused = CliRunner().invoke(app, ["plot", str(empty), "--scan-at", "1"])
    assert refused.exit_code == 1
    assert "no LiDAR scans" in refused.output
    assert not (empty / "path.png").exists()  # refused before anything was drawn
