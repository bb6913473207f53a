"""``simmer compare``: a robot's readings against the band its own settings predict fall
inside it; against a simulator that does not match the robot, the readings outside are named;
the picture is drawn."""

from __future__ import annotations

from pathlib import Path

import pytest

from routine_support import record_routine
from simmer.calibrate.compare import compare, draw_comparison
from simmer.calibrate.groundtruth import hidden_settings, team_config
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
