"""The trail (issue 11, item 5): the path driven so far, with bounded memory, a new piece after
a drag or a reset, exact stopping points, and views that never change once made."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simmer.geometry import Pose
from simmer.view.trail import Trail
from simmer.world.events import PlaceEvent, ResetEvent, StepEvent


def step(trail: Trail, x: float, y: float) -> None:
    trail(StepEvent(0.0, Pose(x, y, 0.0)))


def test_points_are_spaced_and_stops_are_kept() -> None:
    trail = Trail(Pose(0.0, 0.0, 0.0), spacing=0.25)
    for n in range(1, 27):  # 1/16 in a step, to 1.625 in
        step(trail, n / 16, 0.0)
    assert trail.view().points[:, 0].tolist() == [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5]
    step(trail, 1.625, 0.0)  # stopped: where it stopped is a point
    step(trail, 1.625, 0.0)
    assert trail.view().points[-2:, 0].tolist() == [1.5, 1.625]
    assert not np.any(trail.view().points[:, 1])


def test_a_drag_starts_a_new_piece_and_adds_nothing_while_dragging() -> None:
    trail = Trail(Pose(0.0, 0.0, 0.0))
    for n in range(1, 11):
        step(trail, 0.1 * n, 0.0)
    before = len(trail.view().points)
    for n in range(50):  # a drag: the robot placed again and again, steps between
        trail(PlaceEvent(0.0, Pose(5.0, 0.1 * n, 0.0)))
        step(trail, 5.0, 0.1 * n)
    assert len(trail.view().points) == before
    for n in range(1, 6):  # then it drives on from where it was dropped, and stops
        step(trail, 5.0 + 0.1 * n, 4.9)
    step(trail, 5.5, 4.9)
    points = trail.view().points
    assert math.isnan(points[before, 0])
    assert points[before + 1].tolist() == pytest.approx([5.0, 4.9])
    assert points[-1].tolist() == pytest.approx([5.5, 4.9])


def test_memory_is_bounded_and_views_never_change() -> None:
    trail = Trail(Pose(0.0, 0.0, 0.0), spacing=0.2, limit=64)
    first = trail.view()
    kept = []
    for n in range(1, 5000):  # round and round a circle of 10 in: 3000 in driven
        angle = n * 0.01
        step(trail, 10 * math.cos(angle), 10 * math.sin(angle))
        view = trail.view()
        assert len(view.points) <= 64
        if n % 500 == 0:
            kept.append((view, view.points.copy()))
            assert not view.points.flags.writeable
    assert trail.spacing >= 0.2 * 2**5  # thinned again and again
    assert trail.view().generation > first.generation
    for view, points in kept:
        assert np.array_equal(view.points, points)


def test_a_reset_starts_a_new_trail() -> None:
    trail = Trail(Pose(0.0, 0.0, 0.0))
    for n in range(1, 11):
        step(trail, 0.5 * n, 0.0)
    old = trail.view()
    trail(ResetEvent(1.0, 60))
    assert len(trail.view().points) == 0
    assert trail.view().generation != old.generation
    step(trail, 0.0, 0.0)
    step(trail, 0.0, 1.0)
    assert trail.view().points.tolist() == [[0.0, 0.0], [0.0, 1.0]]
    assert len(old.points) == 11
