"""Expected readings (``Simulation.expected``, ``simmer table``): the sensors' noise-free readings,
exactly, and the kinds it cannot answer refused by name."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.geometry import Pose
from simmer.world import Simulation
from simmer.world.expected import SUPPORTED, parse_headings, table

from helpers import EXAMPLES, make_config

pytestmark = pytest.mark.timeout(180)


def quiet_default() -> Simulation:
    """examples/simmer_default.toml (ultrasonic, gyroscope, compass, infrared) with no noise,
    and three time-of-flight sensors (above the block, the other preset, millimetres)."""
    data = tomllib.loads((EXAMPLES / "simmer_default.toml").read_text(encoding="utf-8"))
    for sensor in data["sensors"].values():
        if "error" in sensor:
            sensor["error"] = 0.0
    data["sensors"]["c0"]["bias"] = 7.5  # a compass's bias is part of its noise-free reading
    quiet = {"type": "tof", "error": 0.0, "error_constant": 0.0}
    data["sensors"]["t0"] = quiet | {"position": [0, 2], "height": 4.0}
    data["sensors"]["t1"] = quiet | {"position": [1, 0, 2], "rotation": -60, "preset": "vl53l1x"}
    data["sensors"]["t2"] = quiet | {"rotation": 120, "units": "mm", "mode": "long_range"}
    return Simulation(make_config(data), seed=3)


@pytest.mark.slow
def test_expected_equals_the_sensors_noise_free_readings_at_1000_random_poses() -> None:
    sim = quiet_default()
    kinds = {d.id: type(d).kind for d in sim.robot.sensors.values()}
    ids = [i for i, kind in kinds.items() if kind in SUPPORTED]
    assert {kinds[i] for i in ids} == set(SUPPORTED) - {"lidar"}  # tests/devices/test_lidar.py
    rng = np.random.default_rng(22)
    poses = np.column_stack(
        (
            rng.uniform(-2, sim.maze.width + 2, 1000),  # a few with sensors outside the maze
            rng.uniform(-2, sim.maze.height + 2, 1000),
            rng.uniform(-720, 720, 1000),
        )
    )
    poses[:20] = [sim.block.x, sim.block.y + 10, 180.0]  # facing the block
    wanted = sim.expected(poses, ids)
    for pose, row in zip(poses, wanted, strict=True):
        sim.robot.pose = Pose(*pose)
        assert sim.command(",".join(ids)) == row.tolist(), pose
    seen_block = sim.expected(poses[:20], ids, block=True)
    walls_only = sim.expected(poses[:20], ids, block=False)
    assert (seen_block != walls_only).any()


def test_expected_refuses_the_kinds_it_cannot_answer_by_name() -> None:
    sim = quiet_default()
    with pytest.raises(ValueError, match=r"'g0'.*gyroscope integrates"):
        sim.expected([10.0, 10.0, 0.0], ["g0"])
    with pytest.raises(ValueError, match="no sensor 'u9'"):
        sim.expected([10.0, 10.0, 0.0], ["u9"])
    with pytest.raises(ValueError, match="shape"):
        sim.expected([[1.0, 2.0]], ["u0"])


def test_a_table_is_expected_at_its_grid_and_nan_in_solid_cells() -> None:
    sim = Simulation.from_config()
    headings = parse_headings("0:360:45")
    xs, ys, ids, readings = table(sim, 6.0, headings)
    assert readings.shape == (len(ys), len(xs), 8, 4)
    row, col = 1, 3
    poses = np.column_stack((np.full(8, xs[col]), np.full(8, ys[row]), headings))
    if sim.maze.solid[int(ys[row] // sim.maze.cell), int(xs[col] // sim.maze.cell)]:
        assert np.isnan(readings[row, col]).all()
    else:
        assert np.array_equal(readings[row, col], sim.expected(poses, ids, block=False))
    solid = sim.maze.solid[(ys // sim.maze.cell).astype(int)][:, (xs // sim.maze.cell).astype(int)]
    assert np.isnan(readings[solid]).all()
    assert not np.isnan(readings[~solid]).any()
    with pytest.raises(ValueError, match="START:STOP:STEP"):
        parse_headings("0-360")


@pytest.mark.slow
def test_simmer_table_writes_npz_and_csv_that_agree(tmp_path: Path) -> None:
    runner = CliRunner()
    npz, csv = tmp_path / "t.npz", tmp_path / "t.csv"
    for path in (npz, csv):
        result = runner.invoke(
            app, ["table", "--step", "8", "--headings", "0:360:90", "-o", str(path)]
        )
        assert result.exit_code == 0, result.output
    with np.load(npz) as table_file:  # closed at once: an open file warns in a later test
        data = {name: table_file[name] for name in table_file.files}
    assert list(data["sensors"]) == ["u0", "u1", "u2", "u3"]
    rows = np.loadtxt(csv, delimiter=",", skiprows=1)
    assert csv.read_text().splitlines()[0] == "x,y,heading,u0,u1,u2,u3"
    readings = data["readings"]
    assert len(rows) == int((~np.isnan(readings[..., 0])).sum())
    x, y, h = rows[0, :3]
    i, j, k = list(data["y"]).index(y), list(data["x"]).index(x), list(data["headings"]).index(h)
    assert np.allclose(rows[0, 3:], readings[i, j, k], rtol=1e-5)
    bad = runner.invoke(app, ["table", "-o", str(tmp_path / "t.txt")])
    assert bad.exit_code == 1
    assert ".npz or .csv" in bad.output


def test_simmer_table_has_the_tof_sensors_with_their_out_of_range_value(tmp_path: Path) -> None:
    npz = tmp_path / "tof.npz"
    config = str(EXAMPLES / "tof_rover.toml")
    result = CliRunner().invoke(
        app, ["table", config, "--step", "6", "--headings", "0:360:90", "-o", str(npz)]
    )
    assert result.exit_code == 0, result.output
    with np.load(npz) as table_file:  # closed at once: an open file warns in a later test
        data = {name: table_file[name] for name in ("sensors", "readings", "x", "y", "headings")}
    assert list(data["sensors"]) == ["t0", "t1", "t2"]
    readings = data["readings"]
    nose, sides = readings[..., 0], readings[..., 1:]
    assert (nose == 8190.0).any()  # a VL53L0X with nothing within 1.2 m
    near = sides[np.isfinite(sides)]
    assert near.size
    assert np.all(near == np.round(near))  # whole millimetres
    sim = Simulation.from_config(EXAMPLES / "tof_rover.toml")
    i, j, k = 3, 2, 1
    pose = [data["x"][j], data["y"][i], data["headings"][k]]
    wanted = sim.expected(pose, block=False)[0].astype(readings.dtype)
    np.testing.assert_array_equal(readings[i, j, k], wanted)
