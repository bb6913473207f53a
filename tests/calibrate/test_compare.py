"""``simmer compare``: a robot's readings against the band its own settings predict fall
inside it; against a simulator that does not match the robot, the readings outside are named;
the picture is drawn."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from routine_support import record_routine, record_short_run
from simmer.calibrate.compare import compare, draw_comparison, load_intervals
from simmer.calibrate.groundtruth import hidden_settings, team_config
from simmer.calibrate.routine import plan
from simmer.calibrate.stats import Interval
from simmer.config import load_config
from simmer.config.overrides import with_overrides
from simmer.tap.folder import load_tap_run
from simmer.world.simulation import Simulation

SEEDS = 60
"""Enough for the 0.5th and 99.5th percentiles to be more than the extremes of a few."""


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_a_matching_simulator_holds_the_readings_and_a_wrong_one_names_them(
    tmp_path: Path,
) -> None:
    config = team_config(load_config())
    truth = with_overrides(config, hidden_settings(7, config))
    record_routine(Simulation(truth, seed=7), config, tmp_path / "run")
    run = load_tap_run(tmp_path / "run")
    matching = compare(run, truth, seeds=SEEDS)
    assert len(matching.readings) > 500
    assert matching.inside_fraction >= 0.95
    wrong = compare(run, with_overrides(truth, {"sensors.u1.error": 0.001}), seeds=SEEDS)
    assert wrong.inside_fraction < 0.9
    u1 = [r for r in wrong.readings if r.device == "u1"]
    others = [r for r in wrong.readings if r.device != "u1"]
    assert sum(not r.inside for r in u1) > len(u1) / 2  # its noise is far wider than said
    assert sum(not r.inside for r in others) < 0.05 * len(others)
    named = [line for line in wrong.summary() if line.startswith("  outside: ")]
    assert len(named) == 20  # MAX_NAMED, then how many more
    assert any(line.startswith("  outside: u1 at ") for line in named)
    assert wrong.summary()[-1].startswith("  and ")
    picture = tmp_path / "compare.png"
    draw_comparison(wrong, picture, "a test")
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_fits_intervals_hold_readings_its_point_values_miss(tmp_path: Path) -> None:
    # a robot whose straight drive overshoots by 2%; a fit that put its bias at 0 but could
    # only say it lies within 5% either way (as a short run can): the fitted value alone
    # predicts a band the readings after the leg miss, the interval drawn from holds them
    team = with_overrides(
        team_config(load_config()), {"sensors.*.error": 0.002, "drives.w0.error.y": 0.002}
    )
    robot = Simulation(with_overrides(team, {"drives.w0.bias.y": 0.02}), seed=5)
    record_short_run(robot, team, tmp_path / "run")
    run = load_tap_run(tmp_path / "run")
    point = compare(run, team, seeds=30)
    drawn = compare(run, team, seeds=30, intervals={"drives.w0.bias.y": Interval(0.0, -0.05, 0.05)})
    ahead = plan(team).home[0]  # type: ignore[index]  # the sensor facing along the leg
    moved = [r.device == ahead and r.number > 5 for r in point.readings]  # after the leg
    missed = [p.inside for p, m in zip(point.readings, moved, strict=True) if m]
    held = [d.inside for d, m in zip(drawn.readings, moved, strict=True) if m]
    assert missed.count(False) >= len(missed) / 2, point.summary()
    assert all(held), drawn.summary()
    assert drawn.inside_fraction >= 0.95 > point.inside_fraction
    assert drawn.drawn == ("drives.w0.bias.y",)
    assert "each drawing 1 fitted settings from their intervals" in drawn.summary()[0]
    # only what the uncertain setting moves is widened: the reads before the leg keep
    # the band the sensors' own noise gives
    for p, d in zip(point.readings[:20], drawn.readings[:20], strict=True):
        assert (d.low, d.high) == pytest.approx((p.low, p.high), abs=0.15)


def test_an_interval_is_drawn_as_its_level_says(tmp_path: Path) -> None:
    # a skewed interval (as an error's is): 0.5% of draws below its low end, 0.5% above
    # its high end, half below its value
    interval = Interval(0.02, 0.015, 0.03)
    rng = np.random.default_rng(1)
    draws = np.array([interval.draw(rng) for _ in range(40_000)])
    assert np.mean(draws < 0.015) == pytest.approx(0.005, abs=0.002)
    assert np.mean(draws > 0.03) == pytest.approx(0.005, abs=0.002)
    assert np.mean(draws < 0.02) == pytest.approx(0.5, abs=0.01)


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ('["drives.w0.bias.y"]\nvalue = 0.1\nlow = 0.0\n', "needs finite numbers"),
        ('["drives.w0.bias.y"]\nvalue = 0.1\nlow = 0.2\nhigh = 0.3\nlevel = 0.99\n', "low <="),
        ("value = [", "not TOML"),
    ],
)
def test_a_broken_intervals_file_is_one_plain_error(tmp_path: Path, text: str, says: str) -> None:
    path = tmp_path / "fitted.intervals.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=says) as caught:
        load_intervals(path)
    assert str(path) in str(caught.value)
