"""How well a program localized: its reported poses against the truth.

A program reports its estimate with ``robot.report_pose`` (or the pose it shows); each becomes
an :class:`~simmer.world.events.EstimateEvent` with the true pose beside it. A run is
*localized* from the first estimate after which every estimate is within
:data:`POSITION_TOLERANCE` and :data:`HEADING_TOLERANCE` of the truth, to the end of the run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from simmer.geometry import Pose, wrap_degrees

POSITION_TOLERANCE = 3.0
"""Inches an estimate may be off and count as localized."""
HEADING_TOLERANCE = 15.0
"""Degrees an estimate's heading may be off and count as localized."""
MAX_ERRORS = 100_000
"""Errors kept for the plot (28 simulated minutes at the bound of 60 estimates a second);
later ones still count in the figures."""


def errors(estimate: Pose, truth: Pose) -> tuple[float, float]:
    """(inches, degrees) between an estimate and the truth; the heading error in [0, 180]."""
    heading = abs(wrap_degrees(estimate.heading - truth.heading + 180.0) - 180.0)
    return math.hypot(estimate.x - truth.x, estimate.y - truth.y), heading


def within(position: float, heading: float) -> bool:
    """Whether errors count as localized."""
    return position <= POSITION_TOLERANCE and heading <= HEADING_TOLERANCE


def localized_at(series: Sequence[tuple[float, float, float]]) -> float | None:
    """The time of the first of ``series``' (time, inches, degrees) after which every one is
    within the tolerances (None: the last is not)."""
    since = None
    for time, position, heading in series:
        if not within(position, heading):
            since = None
        elif since is None:
            since = time
    return since


@dataclass(frozen=True)
class LocalizationReport:
    """The figures of a run's estimates (simulated seconds; None: never)."""

    estimates: int
    first_within_at: float | None
    """The first estimate within the tolerances."""
    localized_at: float | None
    """From then on every estimate was within them (the time to localize)."""
    final_position_error: float
    final_heading_error: float

    def summary(self) -> str:
        """One line for the end of a run."""
        if self.localized_at is not None:
            when = f"localized at {self.localized_at:.2f} s"
        elif self.first_within_at is not None:
            when = f"within at {self.first_within_at:.2f} s but not to the end"
        else:
            when = "never within"
        return (
            f"  localization: {self.estimates} estimates; {when} ({POSITION_TOLERANCE:g} in, "
            f"{HEADING_TOLERANCE:g} deg); last off by {self.final_position_error:.2f} in, "
            f"{self.final_heading_error:.1f} deg"
        )

    def as_dict(self) -> dict[str, Any]:
        """Flat figures for report.json and sweep tables."""
        return {
            "estimates": self.estimates,
            "first_within_at": self.first_within_at,
            "localized_at": self.localized_at,
            "final_position_error": self.final_position_error,
            "final_heading_error": self.final_heading_error,
        }


class Tracker:
    """Follows the estimates of one run (part of the run's :class:`~simmer.world.outcome.
    Outcome`)."""

    def __init__(self) -> None:
        self.count = 0
        self.first_within: float | None = None
        self.since: float | None = None
        self.last = (math.nan, math.nan)
        self.series: list[tuple[float, float, float]] = []
        """(time, inches, degrees) of each estimate, up to :data:`MAX_ERRORS`."""

    def add(self, time: float, estimate: Pose, truth: Pose) -> None:
        """One estimate and the truth then."""
        position, heading = errors(estimate, truth)
        self.count += 1
        self.last = (position, heading)
        if len(self.series) < MAX_ERRORS:
            self.series.append((time, position, heading))
        if within(position, heading):
            if self.first_within is None:
                self.first_within = time
            if self.since is None:
                self.since = time
        else:
            self.since = None

    def report(self) -> LocalizationReport | None:
        """The figures so far (None if the program reported no estimate)."""
        if not self.count:
            return None
        return LocalizationReport(self.count, self.first_within, self.since, *self.last)
