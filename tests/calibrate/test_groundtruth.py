"""Ground truth, the whole way: a simulator with hidden settings serves its serial port in
real time, the calibration routine program runs on it through a real tap, and the fit's
intervals hold the hidden settings; the fitted configuration's band holds the readings.
(benchmarks/calibration_recovery.py runs twenty of these and counts.)"""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from simmer.calibrate.groundtruth import trial
from simmer.config import load_config
from simmer.config.overrides import with_overrides


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_one_hidden_robot_behind_the_tap_is_recovered(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    # the robot's busy polls, for this test only: the level is restored after it (set on the
    # logger for good, it silenced the warnings later tests on the same worker look for)
    caplog.set_level(logging.ERROR, logger="simmer")
    # the robot drives twice as fast as the default and holds still for 1.5 s, not 3: the
    # routine's 43 s of driving and holding become about 24 s (its noise is per command, so
    # what is fitted is the same; the gyroscope's drift is told less tightly from the
    # shorter holds, which its interval says). Four times as fast, 17 s, left too few
    # readings in the band for the 95% in 2 runs of 12 (94.8%; 95.1-97.6% otherwise): the
    # tap's timing counts for more the faster the robot moves. Twice as fast: 96.4-97.4%.
    fast = with_overrides(
        load_config(), {"drives.w0.velocity": [0.0, 12.0], "drives.r0.ang_velocity": 240.0}
    )
    result = trial(11, tmp_path / "trial", fast, seeds=100, hold=1.5)  # fewer: a thin band
    missed = [key for key, covered in result.covered.items() if not covered]
    assert len(missed) <= 1, missed
    # the 95%: compare's band carries the fit's intervals (each seed draws the
    # fitted settings from them), so a leg's end where the fitted drive error sits below the
    # robot's, or stops after a turn, are inside what the run could tell of the robot
    assert result.inside >= 0.95, result.inside
    assert (tmp_path / "trial" / "run" / "exchanges.csv").exists()
