"""The lidar kind: its geometry against expected and an independent reference, its range
limits, the block by mounting height, motion skew, noise statistics and its reads."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import tomlkit
from typer.testing import CliRunner

from simmer import Simulation
from simmer.cli import app
from simmer.devices.lidar import ZIGGURAT_R, Lidar, fill_normals, standard_normals

from helpers import default_data, make_sim

QUIET = {
    "range_error": 0.0,
    "range_error_proportional": 0.0,
    "angular_jitter": 0.0,
    "dropout": 0.0,
}


def lidar_data(**settings: Any) -> dict[str, Any]:
    """The default rover with a LiDAR ``l0`` at its centre (settings added)."""
    data = default_data()
    data["sensors"]["l0"] = {"type": "lidar", "position": [0, 0]} | settings
    return data


def lidar(sim: Simulation, device_id: str = "l0") -> Lidar:
    device = sim.robot.devices[device_id]
    assert isinstance(device, Lidar)
    return device


def next_scan(sim: Simulation, device: Lidar) -> None:
    """Step until a new scan has ended."""
    number = device.number
    while device.number == number:
        sim.step()


def open_poses(sim: Simulation, count: int, seed: int) -> np.ndarray:
    """``count`` random poses in open cells, away from the walls by a little."""
    rng = np.random.default_rng(seed)
    maze = sim.maze
    poses = []
    while len(poses) < count:
        x, y = rng.uniform(0.5, maze.width - 0.5), rng.uniform(0.5, maze.height - 0.5)
        if not maze.solid[int(y // maze.cell), int(x // maze.cell)]:
            poses.append((x, y, rng.uniform(0.0, 360.0)))
    return np.array(poses)


def reference_scan(
    segments: np.ndarray, x: float, y: float, headings: np.ndarray, limit: float
) -> np.ndarray:
    """The first segment each beam from (x, y) at ``headings`` meets, every beam against
    every segment in plain NumPy (no Numba, no grid walk): inf if none within ``limit``."""
    rad = np.radians(headings)[:, None]
    dx, dy = -np.sin(rad), np.cos(rad)
    x1, y1, x2, y2 = segments.T
    sx, sy = x2 - x1, y2 - y1
    denom = dx * sy - dy * sx
    wx, wy = x1 - x, y1 - y
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (wx * sy - wy * sx) / denom
        u = (wx * dy - wy * dx) / denom
    hit = (denom != 0.0) & (t >= 0.0) & (u >= -1e-12) & (u <= 1.0 + 1e-12)
    best = np.where(hit, t, np.inf).min(axis=1)
    best[best > limit] = np.inf
    return best


def test_quiet_scan_equals_expected_at_1000_random_poses() -> None:
    # a revolution a step (60 steps a second): a scan at each pose costs two steps, not 12
    sim = make_sim(lidar_data(**QUIET, motion_skew=False, scan_rate=60))
    device = lidar(sim)
    poses = open_poses(sim, 1000, seed=1)
    table = sim.expected(poses, ["l0"])
    assert table.shape == (1000, 360)
    assert (table > 0).mean() > 0.6  # most beams hit a wall: the comparison means something
    for pose, row in zip(poses, table, strict=True):
        sim.robot.pose = sim.robot.pose._replace(x=pose[0], y=pose[1], heading=pose[2])
        sim.step()  # the pose is recorded; the next scan is all made here
        next_scan(sim, device)
        np.testing.assert_array_equal(device.distances, row)


def test_quiet_scan_equals_a_plain_numpy_reference_at_200_poses() -> None:
    data = lidar_data(**QUIET, position=[0.75, -1.25], rotation=30, height=1)
    data["sensors"]["l0"]["min_range"] = 0.0
    sim = make_sim(data)
    device = lidar(sim)
    poses = open_poses(sim, 200, seed=2)
    table = sim.expected(poses, ["l0"])
    segments = np.vstack((sim.maze.segments, sim.block.segments))
    checked = 0
    for pose, row in zip(poses, table, strict=True):
        origin = device.world_pose(sim.robot.pose._replace(x=pose[0], y=pose[1], heading=pose[2]))
        want = reference_scan(
            segments, origin.x, origin.y, origin.heading + device.directions, 472.0
        )
        none = want == np.inf
        np.testing.assert_array_equal(row[none], 0.0)
        np.testing.assert_allclose(row[~none], want[~none], rtol=0.0, atol=1e-6)
        checked += int((~none).sum())
    assert checked > 0.9 * 200 * 360


def test_range_limits_read_zero_as_the_rplidar_reports_no_return() -> None:
    # The robot at (6, 42) facing up: the wall ahead 42 in, the one to the right 6 in.
    sim = make_sim(lidar_data(**QUIET, min_range=10.0, max_range=30.0))
    ahead, right = sim.command("l0-0,l0-270")  # heading 180: beam 270 points to +x
    assert ahead == 0.0  # beyond max_range
    assert right == 0.0  # closer than min_range
    sim = make_sim(lidar_data(**QUIET, min_range=1.0, max_range=60.0))
    ahead, right = sim.command("l0-0,l0-270")
    assert ahead == pytest.approx(42.0, abs=1e-9)
    assert right == pytest.approx(6.0, abs=1e-9)


@pytest.mark.parametrize(("height", "sees"), [(1.0, True), (2.9, True), (3.5, False), (8, False)])
def test_a_low_lidar_sees_the_block_and_a_high_one_does_not(height: float, sees: bool) -> None:
    data = lidar_data(**QUIET, height=height)
    sim = make_sim(data)
    block = sim.block
    device = lidar(sim)
    # Stand 12 in from the block, facing it, where no wall is between.
    sides = [(block.x, block.y - 12.0, 0.0), (block.x, block.y + 12.0, 180.0)]
    sides += [(block.x + 12.0, block.y, 90.0), (block.x - 12.0, block.y, 270.0)]
    walls_only = sim.expected(np.array(sides), ["l0"], block=False)[:, 0]
    poses = np.array([sides[int(np.argmax(walls_only))]])
    with_block = sim.expected(poses, ["l0"])[0, 0]
    walls = sim.expected(poses, ["l0"], block=False)[0, 0]
    assert device.sees_block(sim) is sees
    if sees:
        assert with_block == pytest.approx(12.0 - block.size / 2.0, abs=1e-6)
    else:
        assert with_block == walls
    assert walls > 12.0


@pytest.mark.slow
def test_a_turning_robots_scan_is_smeared_and_a_still_one_is_not() -> None:
    scans = {}
    for skew in (True, False):
        sim = make_sim(lidar_data(**QUIET, motion_skew=skew))
        device = lidar(sim)
        sim.command("r0-360")  # 120 deg/s: 22 degrees within one revolution
        track = [(sim.time, *sim.robot.pose)]  # every step's pose, kept here
        for _ in range(2):
            number = device.number
            while device.number == number:
                sim.step()
                track.append((sim.time, *sim.robot.pose))
        scans[skew] = (device.distances.copy(), np.array(track), device.scan_time, sim)
    skewed, track, end, sim = scans[True]
    # Beam k of n is measured at start + (end - start)·k/n, from the pose the robot had then:
    # interpolated here between the steps around it (the heading unwrapped).
    period = 1.0 / 5.5
    times = end - period + period * np.arange(360) / 360
    headings = np.unwrap(track[:, 3], period=360.0)
    beam_poses = np.column_stack(
        [np.interp(times, track[:, 0], column) for column in (track[:, 1], track[:, 2], headings)]
    )
    assert 20.0 < beam_poses[-1, 2] - beam_poses[0, 2] < 23.0
    for k in range(0, 360, 7):
        want = sim.expected(beam_poses[k : k + 1], ["l0"])[0, k]
        assert skewed[k] == pytest.approx(want, abs=1e-6)
    # The unskewed scan: every beam from the pose at the scan's end.
    still, track, end, sim = scans[False]
    headings = np.unwrap(track[:, 3], period=360.0)
    at_end = np.array(
        [[np.interp(end, track[:, 0], c) for c in (track[:, 1], track[:, 2], headings)]]
    )
    np.testing.assert_allclose(still, sim.expected(at_end, ["l0"])[0], rtol=0.0, atol=1e-6)
    assert (np.abs(skewed - still) > 0.5).sum() > 20


@pytest.mark.slow
def test_noise_statistics_over_100000_beams_match_the_settings() -> None:
    const, prop, drop = 0.05, 0.02, 0.03
    sim = make_sim(
        lidar_data(range_error=const, range_error_proportional=prop, dropout=drop, angular_jitter=0)
    )
    device = lidar(sim)
    truth = sim.expected(np.array([sim.robot.pose]), ["l0"])[0]
    valid = truth > 5.9 + 1.0  # far from min_range, where noise would cut one tail off
    residuals, zeros, beams = [], 0, 0
    both, pairs = 0, 0  # beams next to each other, both valid: both dropped
    paired = valid & np.roll(valid, -1)
    while beams < 100_000:
        next_scan(sim, device)
        dropped = device.distances == 0.0
        both += int((dropped & np.roll(dropped, -1))[paired].sum())
        pairs += int(paired.sum())
        got = device.distances[valid]
        zeros += int((got == 0.0).sum())
        beams += got.size
        kept = got != 0.0
        residuals.append((got[kept] - truth[valid][kept]) / (const + prop * truth[valid][kept]))
    z = np.concatenate(residuals)
    # Standardised by the configured sd: mean 0, sd 1 (4 standard errors at this count).
    assert abs(z.mean()) < 4 / math.sqrt(z.size)
    assert abs(z.std() - 1.0) < 4 / math.sqrt(2 * z.size)
    rate = zeros / beams
    assert abs(rate - drop) < 4 * math.sqrt(drop * (1 - drop) / beams)
    # Each beam dropped independently (drops drawn as the gaps between them): two neighbours
    # both dropped at the chance squared.
    assert abs(both / pairs - drop**2) < 4 * math.sqrt(drop**2 / pairs)


def normal_tail(c: float) -> float:
    """The chance that a standard normal lies beyond ``c`` on either side."""
    return math.erfc(c / math.sqrt(2.0))


def test_the_noises_normals_have_a_standard_normals_moments_and_tails() -> None:
    # The LiDAR's normals come from the device's bit stream by the ziggurat method
    # (standard_normals): 2,000,000 of them, each figure within 5 standard errors.
    n = 2_000_000
    z = np.empty(n)
    standard_normals(np.random.default_rng(11), z)
    assert abs(z.mean()) < 5 / math.sqrt(n)
    assert abs(z.var() - 1.0) < 5 * math.sqrt(2 / n)
    assert abs(np.mean(z**3)) < 5 * math.sqrt(15 / n)  # skewness 0
    assert abs(np.mean(z**4) - 3.0) < 5 * math.sqrt(96 / n)  # kurtosis 3
    # The tails, the ziggurat's tail beyond r (its own algorithm) included, on both sides.
    for c in (1.0, 2.0, 3.0, ZIGGURAT_R, 4.0):
        expected = n * normal_tail(c)
        assert abs(np.count_nonzero(np.abs(z) > c) - expected) < 5 * math.sqrt(expected), c
    assert abs(
        np.count_nonzero(z > ZIGGURAT_R) - np.count_nonzero(z < -ZIGGURAT_R)
    ) < 5 * math.sqrt(n * normal_tail(ZIGGURAT_R))
    # The whole shape: 60 bins of equal chance, a chi-square well within its spread.
    cuts = np.quantile(np.random.default_rng(0).standard_normal(4_000_000), np.linspace(0, 1, 61))
    cuts[0], cuts[-1] = -np.inf, np.inf
    chances = np.diff([0.5 * math.erfc(-c / math.sqrt(2.0)) for c in cuts])
    counts = np.histogram(z, cuts)[0]
    chi2 = float((((counts - n * chances) ** 2) / (n * chances)).sum())
    assert chi2 < 59 + 5 * math.sqrt(2 * 59)


def test_the_normals_of_a_seed_are_the_same_however_the_bits_run_out() -> None:
    # fill_normals stops when its bits run out; standard_normals then draws more: a seed
    # always gives the same normals, and a short supply fills only part.
    a, b = np.empty(5000), np.empty(5000)
    standard_normals(np.random.default_rng(3), a)
    standard_normals(np.random.default_rng(3), b)
    np.testing.assert_array_equal(a, b)
    bits = np.random.default_rng(3).bit_generator.random_raw(100)  # 200 words, a normal each
    short = np.zeros(5000)
    filled = fill_normals(bits, short, 0)
    assert 180 <= filled <= 200
    assert np.all(short[filled:] == 0.0)
    assert fill_normals(bits, short, 5000) == 5000


def test_angular_jitter_moves_beams_by_its_sd() -> None:
    sim = make_sim(lidar_data(**(QUIET | {"angular_jitter": 0.5})))
    device = lidar(sim)
    # A wall straight ahead at distance D: a beam off by a small angle e reads D / cos(e).
    d = sim.expected(np.array([sim.robot.pose]), ["l0"])[0, 0]
    readings = []
    for _ in range(300):
        next_scan(sim, device)
        readings.append(device.distances[0])
    e = np.degrees(np.arccos(np.minimum(d / np.array(readings), 1.0)))
    # |e| of a normal with sd 0.5 has mean 0.5·sqrt(2/pi)
    assert np.mean(e) == pytest.approx(0.5 * math.sqrt(2 / math.pi), rel=0.15)


def test_the_same_seed_gives_the_same_scans_and_another_seed_others() -> None:
    def scans(seed: int) -> list[np.ndarray]:
        sim = make_sim(lidar_data(), seed=seed)
        sim.command("r0-90,w0-0")
        out = []
        for _ in range(5):
            next_scan(sim, lidar(sim))
            out.append(lidar(sim).distances.copy())
        return out

    first, again, other = scans(7), scans(7), scans(8)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)
    assert any(not np.array_equal(a, b) for a, b in zip(first, other, strict=True))


def test_reads_a_beam_by_angle_the_beams_and_the_scan_number() -> None:
    sim = make_sim(lidar_data(**QUIET, beams=400))
    device = lidar(sim)
    assert sim.command("l0--1,l0--2") == [400.0, 1.0]  # the scan made at the start pose
    values = sim.command("l0-0,l0-90,l0-90.4,l0-359.9")
    assert values[0] == device.distances[0]
    assert values[1] == values[2] == device.distances[100]
    assert values[3] == device.distances[0]  # 359.9 is nearest beam 0
    next_scan(sim, device)
    assert sim.command("l0--2") == [2.0]
    assert sim.time == pytest.approx(1 / 5.5, abs=1 / 60)
    for bad in ("l0-360", "l0--3", "l0--0.5"):
        assert math.isnan(sim.command(bad)[0])


def test_a_whole_scan_read_answers_each_scan_as_it_is_while_the_robot_drives() -> None:
    """The client's whole-scan message (``l0--2`` and every beam's nominal angle, read from a
    list made at a scan's first read) answers the latest scan each time, never the one before,
    and off-grid angles (``-0``, ``0.4``) the nearest beam's distance."""
    sim = make_sim(lidar_data(beams=180))
    device = lidar(sim)
    angles = np.arange(180) * 2.0
    message = ",".join(["l0--2", *(f"l0-{a!r}" for a in angles.tolist())])
    sim.command("w0-24")
    previous: list[float] = []
    for number in range(1, 7):
        values = sim.command(message)
        assert values[0] == number
        assert values[1:] == device.distances.tolist()
        assert values[1:] != previous  # the robot moved: a new scan
        assert sim.command("l0--0,l0-0.4,l0-3.1") == [values[1], values[1], values[3]]
        previous = values[1:]
        next_scan(sim, device)


def test_max_range_must_be_above_min_range() -> None:
    from simmer.errors import ConfigError

    with pytest.raises(ConfigError, match="max_range"):
        make_sim(lidar_data(min_range=50.0, max_range=40.0))


def test_too_many_beams_names_the_limit() -> None:
    from simmer.errors import ConfigError

    with pytest.raises(ConfigError, match="MAX_BEAMS"):
        make_sim(lidar_data(beams=1000))


def test_the_table_at_heading_0_rotated_is_the_scan_at_every_heading(tmp_path: Path) -> None:
    data = lidar_data(**QUIET, position=[1.0, -0.5], rotation=90)
    config = tmp_path / "rover.toml"
    config.write_text(tomlkit.dumps(data), encoding="utf-8")
    npz = tmp_path / "lidar.npz"
    result = CliRunner().invoke(
        app, ["table", str(config), "--sensor", "l0", "--step", "3", "-o", str(npz)]
    )
    assert result.exit_code == 0, result.output
    table = np.load(npz)
    readings = table["readings"]
    assert readings.shape == (len(table["y"]), len(table["x"]), 360)
    np.testing.assert_array_equal(table["angles"], np.arange(360) * 1.0)
    sim = make_sim(data)
    device = lidar(sim)
    rng = np.random.default_rng(3)
    cells, poses = [], []
    for _ in range(200):
        i, j = rng.integers(len(table["y"])), rng.integers(len(table["x"]))
        if np.isnan(readings[i, j, 0]):
            continue
        heading = float(rng.integers(360))  # the robot's; the LiDAR faces heading + 90
        # the robot pose that puts the LiDAR's centre at the table's (x, y)
        rad = math.radians(heading)
        px, py = device.position
        x = table["x"][j] - (px * math.cos(rad) - py * math.sin(rad))
        y = table["y"][i] - (px * math.sin(rad) + py * math.cos(rad))
        cells.append((i, j))
        poses.append((x, y, heading))
    wanted = sim.expected(np.array(poses), ["l0"], block=False)  # one call for them all
    checked = 0
    for (i, j), (_, _, heading), want in zip(cells, poses, wanted, strict=True):
        got = np.roll(readings[i, j], -round((heading + 90.0) * 360 / 360))
        # float32 in the file. A diagonal beam from this grid (x - y a multiple of 12 in)
        # runs exactly through walls' corners, and one rounding decides whether it slips
        # between them: those are ties, and the only beams allowed to differ.
        off = np.flatnonzero(np.abs(got - want) > 1e-4 + 1e-6 * want)
        assert set(((off + heading + 90.0) % 90.0).tolist()) <= {45.0}, off
        checked += 1
    assert checked > 100
    both = CliRunner().invoke(
        app, ["table", str(config), "--sensor", "l0", "--sensor", "u0", "-o", str(npz)]
    )
    assert both.exit_code == 1
    assert "--sensor l0 only" in both.output


def test_a_config_py_faking_a_lidar_with_a_ring_of_ultrasonics_still_loads() -> None:
    from helpers import SIMMER_PY

    sim = Simulation.from_config(SIMMER_PY / "lidar_ring" / "config.py")
    ring = [f"{'abcd'[k // 10]}{k % 10}" for k in range(36)]
    assert all(sim.robot.sensors[i].kind == "ultrasonic" for i in ring)
    readings = sim.command(",".join(ring))
    assert all(0 < r < 433 for r in readings)
    # What docs/migrating.md says replaces it: a lidar with 36 beams at the ring's centre.
    data = lidar_data(**QUIET, beams=36, min_range=0.0, height=5)
    want = make_sim(data).expected(np.array([sim.robot.pose]), ["l0"])[0]
    np.testing.assert_allclose(readings, want, atol=1e-9)


def test_a_run_with_a_noisy_lidar_replays_bit_for_bit() -> None:
    from simmer.world.events import Event
    from simmer.world.replay import replay

    events: list[Event] = []
    sim = make_sim(lidar_data(), seed=11)
    sim.add_observer(events.append)
    scans = []
    for message in ("r0-90", "w0-12", "r0--45"):
        sim.command(message)
        while sim.robot.any_drive_moving:
            sim.step()
            if sim.steps % 5 == 0:
                scans.append(sim.command("l0--2," + ",".join(f"l0-{a}" for a in range(360))))
    result = replay(sim.config, sim.seed, events)
    assert result.differences == []  # every reply, each beam of every scan read, bit for bit
    assert len(scans) > 20
    np.testing.assert_array_equal(lidar(result.sim).distances, lidar(sim).distances)
