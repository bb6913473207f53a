"""SimMeR's ``utilities`` helpers, for device classes written for the original SimMeR.

A student's device (from the original's ``devices/template.py``) does ``import utilities`` and
calls these by the original's names; :mod:`simmer.compat.standins` exposes exactly the names in
``__all__`` as that module. They are reimplemented here from their documented behaviour
(BEHAVIOUR §6.3), not copied. Points may be lists, tuples or ``pygame.math.Vector2`` stand-ins;
a segment is a pair of points ``[start, end]``.

Two helpers need the running simulation: :func:`add_error` draws from the generator and
:func:`in_block` reads the ``CONFIG`` module of the device being simulated. The adapter
(:mod:`simmer.compat.template`) puts both in :data:`CONTEXT` before each call, so a seeded run
stays repeatable.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, TypeVar

import numpy as np

TOLERANCE = 1e-9
"""Inches: points this close to a line or an end count as on it (absorbs rounding)."""


class PointLike(Protocol):
    """A 2-D point indexable as ``p[0]``, ``p[1]``: a list, a tuple or a ``Vector2``."""

    def __getitem__(self, index: int, /) -> Any: ...


P = TypeVar("P", bound=PointLike)
T = TypeVar("T")


@dataclass
class Context:
    """What the helpers use from the running simulation; the adapter sets it before each call.

    ``rng`` is the generator of the device being simulated (so noise is seeded); ``config`` is
    its ``CONFIG`` module (``walls``, ``wall_segment_length``...), None outside a simulation.
    """

    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))
    config: Any = None


CONTEXT = Context()


# ----------------------------------------------------------------------------- noise


def add_error(
    value: float, pct_error: float, bounds: Sequence[float] | None = None, sigma: float = 2.0
) -> float:
    """SimMeR's percent error: ``value + N(0, sigma) · pct_error · value``.

    Clamped to ``bounds = [low, high]`` when bounds are given (an empty list means none). No
    number is drawn when ``pct_error`` is 0, as the built-in devices do.
    """
    noisy = value
    if pct_error:
        noisy = value + float(CONTEXT.rng.normal(0.0, sigma)) * pct_error * value
    if bounds:
        noisy = min(max(noisy, bounds[0]), bounds[1])
    return noisy


# ----------------------------------------------------------------------------- segments


def _xy(point: PointLike) -> tuple[float, float]:
    """A point of any accepted kind as a tuple of floats."""
    return float(point[0]), float(point[1])


def _cross(ax: float, ay: float, bx: float, by: float) -> float:
    """The z component of the cross product of (ax, ay) and (bx, by)."""
    return ax * by - ay * bx


def _on_segment(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Whether ``p`` lies on segment ``a``-``b`` (within :data:`TOLERANCE`)."""
    ex, ey = b[0] - a[0], b[1] - a[1]
    px, py = p[0] - a[0], p[1] - a[1]
    length = math.hypot(ex, ey)
    if length == 0.0:
        return math.hypot(px, py) <= TOLERANCE
    if abs(_cross(px, py, ex, ey)) > TOLERANCE * length:  # farther than TOLERANCE from the line
        return False
    along = px * ex + py * ey
    return -TOLERANCE * length <= along <= length * (length + TOLERANCE)


def collision(
    segment1: Sequence[PointLike], segment2: Sequence[PointLike]
) -> list[tuple[float, float]]:
    """Where two segments meet, as a list of ``(x, y)`` points.

    ``[]`` when they do not meet; one point where they cross (also when an end of one touches
    the other); for collinear segments that overlap or touch, each end of either segment that
    lies on the other one, each point once.
    """
    a, b = _xy(segment1[0]), _xy(segment1[1])
    c, d = _xy(segment2[0]), _xy(segment2[1])
    d1x, d1y = b[0] - a[0], b[1] - a[1]
    d2x, d2y = d[0] - c[0], d[1] - c[1]
    len1, len2 = math.hypot(d1x, d1y), math.hypot(d2x, d2y)
    denominator = _cross(d1x, d1y, d2x, d2y)
    if abs(denominator) > 1e-12 * len1 * len2:  # not parallel: one crossing point, or none
        ox, oy = c[0] - a[0], c[1] - a[1]
        t = _cross(ox, oy, d2x, d2y) / denominator
        u = _cross(ox, oy, d1x, d1y) / denominator
        slack1, slack2 = TOLERANCE / len1, TOLERANCE / len2
        if -slack1 <= t <= 1.0 + slack1 and -slack2 <= u <= 1.0 + slack2:
            return [(a[0] + t * d1x, a[1] + t * d1y)]
        return []
    found: list[tuple[float, float]] = []
    for point, start, end in ((a, c, d), (b, c, d), (c, a, b), (d, a, b)):
        if point not in found and _on_segment(point, start, end):
            found.append(point)
    return found


def _side(a: tuple[float, float], b: tuple[float, float], p: tuple[float, float]) -> int:
    """Which side of line ``a``-``b`` the point ``p`` is on: -1, 1, or 0 on the line."""
    cross = _cross(b[0] - a[0], b[1] - a[1], p[0] - a[0], p[1] - a[1])
    if abs(cross) <= TOLERANCE * math.hypot(b[0] - a[0], b[1] - a[1]):
        return 0
    return 1 if cross > 0 else -1


def _in_box(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Whether ``p`` is within the bounding box of ``a`` and ``b`` (within TOLERANCE)."""
    return all(min(a[i], b[i]) - TOLERANCE <= p[i] <= max(a[i], b[i]) + TOLERANCE for i in (0, 1))


def check_collision_fast(s1: Sequence[PointLike], s2: Sequence[PointLike]) -> bool:
    """Whether two segments meet (touching and collinear overlap count), by side tests only.

    Cheaper than :func:`collision` because no point is computed; the two always agree.
    """
    a, b = _xy(s1[0]), _xy(s1[1])
    c, d = _xy(s2[0]), _xy(s2[1])
    c_side, d_side = _side(a, b, c), _side(a, b, d)
    a_side, b_side = _side(c, d, a), _side(c, d, b)
    if c_side * d_side < 0 and a_side * b_side < 0:
        return True
    return (
        (c_side == 0 and _in_box(c, a, b))
        or (d_side == 0 and _in_box(d, a, b))
        or (a_side == 0 and _in_box(a, c, d))
        or (b_side == 0 and _in_box(b, c, d))
    )


def closest(start: PointLike, test_pts: Sequence[P]) -> tuple[P | list[P], float]:
    """The point of ``test_pts`` nearest ``start`` and its distance; ``([], nan)`` if none."""
    point, squared = closest_fast(start, test_pts)
    return point, math.sqrt(squared)


def closest_fast(start: PointLike, test_pts: Sequence[P]) -> tuple[P | list[P], float]:
    """Like :func:`closest` but gives the squared distance (no square root: faster to compare)."""
    if not test_pts:
        return [], math.nan
    x, y = _xy(start)
    squares = [(float(p[0]) - x) ** 2 + (float(p[1]) - y) ** 2 for p in test_pts]
    best = min(range(len(squares)), key=squares.__getitem__)
    return test_pts[best], squares[best]


def angle(segment1: Sequence[PointLike], segment2: Sequence[PointLike]) -> float:
    """The acute angle between two segments' directions, in degrees (0 to 90).

    The original returned None whenever the raw difference of the two directions was at most
    90 degrees; this returns the angle in every case.
    """
    (ax, ay), (bx, by) = _xy(segment1[0]), _xy(segment1[1])
    (cx, cy), (dx, dy) = _xy(segment2[0]), _xy(segment2[1])
    difference = math.degrees(math.atan2(by - ay, bx - ax) - math.atan2(dy - cy, dx - cx))
    difference = abs(difference) % 180.0
    return min(difference, 180.0 - difference)


# ----------------------------------------------------------------------------- the robot


def simulate_sensors(environment: Mapping[str, Any], sensor_ids: Iterable[str]) -> None:
    """Have each listed sensor of ``environment['ROBOT']`` measure (value 0); unknown ids skip."""
    sensors = environment["ROBOT"].sensors
    for sensor_id in sensor_ids:
        if sensor_id in sensors:
            sensors[sensor_id].simulate(0, environment)


def in_block(vec: PointLike) -> bool:
    """Whether the point lies in a solid (0) cell of ``CONFIG.walls``; False outside the maze.

    Cells are ``CONFIG.wall_segment_length`` square, the first row at the top; a point on a
    cell edge belongs to the cell to its right / below.
    """
    config = CONTEXT.config
    if config is None:
        raise RuntimeError(
            "utilities.in_block needs the running configuration: call it from your device's "
            "simulate or update method"
        )
    x, y = _xy(vec)
    cell = float(config.wall_segment_length)
    walls = config.walls
    row, col = math.floor(y / cell), math.floor(x / cell)
    return 0 <= row < len(walls) and 0 <= col < len(walls[row]) and walls[row][col] == 0


# ----------------------------------------------------------------------------- wall lists


def is_vertical(segment: Sequence[PointLike]) -> bool:
    """Whether both ends have the same x."""
    return float(segment[0][0]) == float(segment[1][0])


def slopeIntercept(segment: Sequence[PointLike]) -> tuple[float, float]:  # noqa: N802 (SimMeR's name)
    """``(slope, intercept)`` of the line ``y = slope · x + intercept`` through the segment.

    A vertical segment gives ``(inf, x)``: it has no y-intercept, and its x identifies the line.
    """
    (x1, y1), (x2, y2) = _xy(segment[0]), _xy(segment[1])
    if x1 == x2:
        return math.inf, x1
    slope = (y2 - y1) / (x2 - x1)
    return slope, y1 - slope * x1


def _key(item: Any) -> Hashable:
    """A hashable value standing for ``item`` (nested lists and Vector2s become tuples)."""
    if isinstance(item, str) or not isinstance(item, Iterable):
        return item
    return tuple(_key(part) for part in item)


def remove_duplicates(sorted_list: Sequence[T]) -> list[T]:
    """The elements that occur exactly once, in their order (items that repeat are dropped).

    Elements are compared by value, so lists and Vector2s work; the list need not be sorted.
    """
    keys = [_key(item) for item in sorted_list]
    counts = Counter(keys)
    return [item for item, key in zip(sorted_list, keys, strict=True) if counts[key] == 1]


def _merge_runs(pieces: list[tuple[P, P]], axis: int) -> list[list[P]]:
    """Merge collinear pieces (each ordered low to high along ``axis``) that touch or overlap."""
    pieces.sort(key=lambda piece: float(piece[0][axis]))
    merged: list[list[P]] = []
    low, high = pieces[0]
    for start, end in pieces[1:]:
        if float(start[axis]) <= float(high[axis]) + TOLERANCE:
            if float(end[axis]) > float(high[axis]):
                high = end
        else:
            merged.append([low, high])
            low, high = start, end
    merged.append([low, high])
    return merged


def _merge_lines(
    segments: Sequence[Sequence[P]], vertical: bool
) -> tuple[list[list[P]], list[list[P]]]:
    """Merged segments of one kind (vertical or not), and the other kind's segments as given."""
    axis = 1 if vertical else 0
    lines: dict[tuple[float, float], list[tuple[P, P]]] = {}
    others: list[list[P]] = []
    for segment in segments:
        if is_vertical(segment) != vertical:
            others.append(list(segment))
            continue
        first, second = segment[0], segment[1]
        ordered = (first, second) if float(first[axis]) <= float(second[axis]) else (second, first)
        slope, intercept = slopeIntercept(segment)
        lines.setdefault((round(slope, 9), round(intercept, 9)), []).append(ordered)
    merged = [piece for pieces in lines.values() for piece in _merge_runs(pieces, axis)]
    return merged, others


def merge_sloped_line_segments(segments: Sequence[Sequence[P]]) -> list[list[P]]:
    """Merge non-vertical segments that lie on one line and touch or overlap.

    Each merged segment runs from its lowest-x end to its highest-x end (the given point
    objects). Vertical segments are passed through unchanged, after the merged ones.
    """
    merged, others = _merge_lines(segments, vertical=False)
    return merged + others


def merge_vertical_line_segments(segments: Sequence[Sequence[P]]) -> list[list[P]]:
    """Merge vertical segments that lie on one line and touch or overlap.

    Each merged segment runs from its lowest-y end to its highest-y end (the given point
    objects). Other segments are passed through unchanged, before the merged ones.
    """
    merged, others = _merge_lines(segments, vertical=True)
    return others + merged


def optimize_walls(segments: Sequence[Sequence[P]]) -> list[list[P]]:
    """The wall list reduced: edges given twice dropped, collinear touching edges merged.

    An edge shared by two neighbouring solid cells appears twice (in either direction) and is no
    wall; what is left is merged into as few segments as possible.
    """
    ordered = [sorted(segment, key=_xy) for segment in segments]
    return merge_vertical_line_segments(merge_sloped_line_segments(remove_duplicates(ordered)))


__all__ = [
    "add_error",
    "angle",
    "check_collision_fast",
    "closest",
    "closest_fast",
    "collision",
    "in_block",
    "is_vertical",
    "merge_sloped_line_segments",
    "merge_vertical_line_segments",
    "optimize_walls",
    "remove_duplicates",
    "simulate_sensors",
    "slopeIntercept",
]
