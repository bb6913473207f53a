"""The time-of-flight kind (``tof``): its presets' range limits, field of view and out-of-range
values, its ranging error, millimetres, the block by height, and its drawn beam."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from simmer import Simulation
from simmer.config.overrides import with_overrides
from simmer.devices import Segment
from simmer.devices.tof import MM_PER_INCH, PRESETS
from simmer.errors import ConfigError
from simmer.geometry import Pose
from simmer.localize.mapdata import map_data

from helpers import default_data, make_config, make_sim

CORRIDOR = 66.0
"""From the default start (6, 42), facing +x (heading 270), the open row runs 66 in to a wall;
the row's own walls are 6 in above and below."""


def tof_sim(seed: int | None = None, **settings: Any) -> Any:
    """The default rover with one time-of-flight sensor ``t0`` at its centre facing +x."""
    data = default_data()
    data["sensors"]["t0"] = {"type": "tof", "rotation": 90} | settings
    return make_sim(data, seed=seed)


QUIET = {"error": 0.0, "error_constant": 0.0}
NARROW = QUIET | {"fov": 1.0}  # the edge rays stay clear of the row's walls


@pytest.mark.parametrize(
    ("preset", "mode", "reach_mm"),
    [
        ("vl53l0x", "default", 1200.0),
        ("vl53l0x", "high_speed", 1200.0),
        ("vl53l0x", "long_range", 2000.0),
        ("vl53l1x", "short", 1300.0),
        ("vl53l1x", "medium", 2900.0),
        ("vl53l1x", "long", 3600.0),
    ],
)
def test_a_mode_reads_a_wall_within_its_range_and_the_out_of_range_value_beyond(
    preset: str, mode: str, reach_mm: float
) -> None:
    sim = tof_sim(preset=preset, mode=mode, **NARROW)
    reach = reach_mm / MM_PER_INCH
    beyond = PRESETS[preset].out_of_range
    (reading,) = sim.command("t0")
    assert reading == (pytest.approx(CORRIDOR, abs=1e-9) if reach > CORRIDOR else beyond)
    # walk toward the wall: the reading appears exactly when the wall comes within reach
    for x in (6.0, 20.0, 30.0, 40.0, 60.0):
        sim.robot.pose = Pose(x, 42.0, 180.0)
        distance = 72.0 - x
        (reading,) = sim.command("t0")
        assert reading == (pytest.approx(distance, abs=1e-9) if distance < reach else beyond), x


def test_the_out_of_range_values_are_the_real_drivers() -> None:
    assert tof_sim(**NARROW).command("t0") == [8190.0]  # VL53L0X: Pololu, ST's API
    assert tof_sim(preset="vl53l1x", mode="short", **NARROW).command("t0") == [-1.0]  # Adafruit
    assert tof_sim(out_of_range=999.0, **NARROW).command("t0") == [999.0]
    assert tof_sim(units="mm", **NARROW).command("t0") == [8190.0]  # never converted


@pytest.mark.parametrize(("preset", "fov"), [("vl53l0x", 25.0), ("vl53l1x", 27.0)])
def test_the_cone_is_the_presets_field_of_view(preset: str, fov: float) -> None:
    # Three rays at -fov/3, 0, +fov/3 (the ultrasonic fan's spacing): the edge rays meet the
    # row's walls 6 in away at 6 / sin(fov / 3), nearer than the far wall.
    sim = tof_sim(preset=preset, mode="long_range" if preset == "vl53l0x" else "long", **QUIET)
    (reading,) = sim.command("t0")
    assert reading == pytest.approx(6.0 / math.sin(math.radians(fov / 3.0)), abs=1e-9)
    # a narrower cone of one's own reaches the far wall
    assert tof_sim(fov=10.0, mode="long_range", **QUIET).command("t0") == [
        pytest.approx(CORRIDOR, abs=1e-9)
    ]
    # one ray: a beam with no width
    assert tof_sim(num_rays=1, mode="long_range", **QUIET).command("t0") == [
        pytest.approx(CORRIDOR, abs=1e-9)
    ]


@pytest.mark.parametrize(
    ("settings", "sd_at_40"),
    [
        ({}, 0.015 * 40.0),  # vl53l0x default: ±3 % as two standard deviations
        ({"mode": "high_speed"}, 0.025 * 40.0),
        ({"preset": "vl53l1x"}, 10.0 / MM_PER_INCH),  # ±20 mm
        ({"error": 0.01, "error_constant": 0.2}, 0.2 + 0.01 * 40.0),
    ],
)
def test_the_ranging_error_has_the_configured_spread(
    settings: dict[str, Any], sd_at_40: float
) -> None:
    sim = tof_sim(seed=5, fov=1.0, **settings)
    sim.robot.pose = Pose(32.0, 42.0, 180.0)  # the wall 40 in away
    readings = np.array(sim.command(",".join(["t0"] * 1000)) + sim.command(",".join(["t0"] * 1000)))
    assert readings.mean() == pytest.approx(40.0, abs=4 * sd_at_40 / math.sqrt(2000))
    assert readings.std() == pytest.approx(sd_at_40, rel=0.08)  # 2,000 draws: sd within ~3 %
    again = tof_sim(seed=5, fov=1.0, **settings)
    again.robot.pose = Pose(32.0, 42.0, 180.0)
    assert again.command("t0,t0,t0") == readings[:3].tolist()  # the same seed, the same noise


def test_the_ranging_error_is_the_streams_normal_of_that_spread_draw_for_draw() -> None:
    # drawn from a block of N(0, 2) values times sd / 2: rng.normal(0, sd) to the bit, in order
    sim = tof_sim(seed=9, fov=1.0)
    t0 = sim.robot.devices["t0"]
    stream = sim.stream("device:t0")
    drawn = 0
    for x in np.linspace(20.0, 60.0, 150):
        sim.robot.pose = Pose(float(x), 42.0, 180.0)
        distance = t0.distance(sim)
        if distance >= t0.max_range:  # no return: no draw
            assert sim.command("t0") == [t0.out_of_range]
            continue
        sd = t0.error_constant + t0.error * distance
        assert sim.command("t0") == [max(distance + float(stream.normal(0.0, sd)), 0.0)]
        drawn += 1
    assert drawn > 50


def test_millimetres_are_whole_as_the_drivers_give_them() -> None:
    sim = tof_sim(units="mm", mode="long_range", **NARROW)
    sim.robot.pose = Pose(10.3, 42.0, 180.0)
    assert sim.command("t0") == [round((72.0 - 10.3) * MM_PER_INCH)]
    noisy = tof_sim(units="mm", seed=1, fov=1.0, mode="long_range")
    values = noisy.command(",".join(["t0"] * 50))
    assert all(v == int(v) for v in values)
    assert len(set(values)) > 5


def test_the_block_is_seen_by_a_low_sensor_and_not_by_a_high_one() -> None:
    data = default_data()
    data["block_position"] = [40.0, 42.0]  # in the row, 34 in ahead of the robot's centre
    low = {"type": "tof", "rotation": 90, "mode": "long_range", **NARROW}
    data["sensors"]["t0"] = low | {"height": 2.0}
    data["sensors"]["t1"] = low | {"height": 9.0}
    sim = make_sim(data)
    low_read, high_read = sim.command("t0,t1")
    assert low_read == pytest.approx(40.0 - 1.5 - 6.0, abs=1e-9)  # the block's near face
    assert high_read == pytest.approx(CORRIDOR, abs=1e-9)


def test_the_beam_is_drawn_after_a_read_and_not_later() -> None:
    sim = tof_sim(mode="long_range", **QUIET)

    def beam() -> list[Segment]:
        return [s for s in sim.shapes() if isinstance(s, Segment) and s.color == (255, 0, 255)]

    assert beam() == []  # nothing read yet
    sim.command("t0")
    assert len(beam()) == 3
    assert {round(math.dist(s.start, s.end), 6) for s in beam()} == {
        round(CORRIDOR, 6),
        round(6.0 / math.sin(math.radians(25.0 / 3.0)), 6),
    }
    sim.step(40)  # 2/3 s: past visible_measurement_time
    assert beam() == []


def test_a_mode_the_preset_lacks_is_refused_by_name() -> None:
    data = default_data()
    data["sensors"]["t0"] = {"type": "tof", "preset": "vl53l1x", "mode": "long_range"}
    with pytest.raises(ConfigError, match=r"mode.*vl53l1x has the ranging modes 'short'"):
        make_config(data)


def test_the_map_a_program_gets_has_the_tof_and_encoder_figures() -> None:
    data = default_data()
    data["sensors"]["t0"] = {"type": "tof", "preset": "vl53l1x", "mode": "short", "units": "mm"}
    data["sensors"]["e0"] = {"type": "encoder", "wheel": "right", "counts_per_rev": 1440}
    mounts = {m["id"]: m for m in map_data(make_sim(data))["devices"]}
    assert mounts["t0"]["fov"] == 27.0
    assert mounts["t0"]["max_range"] == pytest.approx(1300.0 / MM_PER_INCH)
    assert (mounts["t0"]["out_of_range"], mounts["t0"]["units"]) == (-1.0, "mm")
    assert (mounts["e0"]["wheel"], mounts["e0"]["counts_per_rev"]) == ("right", 1440.0)


def test_a_sweeps_override_of_the_mode_is_checked_as_a_file_is() -> None:
    data = default_data()
    data["sensors"]["t0"] = {"type": "tof", "rotation": 90, **NARROW}
    config = make_config(data)
    longer = with_overrides(config, {"sensors.t0.mode": "long_range"})
    assert Simulation(longer).command("t0") == [pytest.approx(CORRIDOR, abs=1e-9)]
    with pytest.raises(ConfigError, match=r"sensors\.t0\.mode.*'high_speed', 'long_range'"):
        with_overrides(config, {"sensors.t0.mode": "long"}, "the sweep")
