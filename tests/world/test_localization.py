"""Localization figures: when a program's estimates count as localized."""

from __future__ import annotations

import pytest

from simmer.geometry import Pose
from simmer.world.localization import LocalizationReport, Tracker, errors, localized_at

pytestmark = pytest.mark.timeout(180)


def test_localized_is_the_first_estimate_within_from_which_it_stays_within() -> None:
    truth = Pose(10.0, 10.0, 359.0)
    assert errors(Pose(10.0, 13.0, 1.0), truth) == pytest.approx((3.0, 2.0))
    tracker = Tracker()
    for time, pose in [
        (1.0, Pose(40.0, 10.0, 0.0)),
        (2.0, Pose(11.0, 10.0, 5.0)),  # within
        (3.0, Pose(11.0, 10.0, 40.0)),  # heading off: out again
        (4.0, Pose(12.0, 11.0, 350.0)),  # within from here on
        (5.0, Pose(10.0, 10.0, 359.0)),
    ]:
        tracker.add(time, pose, truth)
    report = tracker.report()
    assert report == LocalizationReport(5, 2.0, 4.0, 0.0, 0.0)
    assert localized_at([(t, p, h) for t, p, h in tracker.series]) == 4.0
    assert Tracker().report() is None
