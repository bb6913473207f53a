"""Vectorised and compiled geometry: rays, segments, polygons and the maze grid.

Everything here works on plain floats and NumPy arrays in inches and degrees, in the world
frame of BEHAVIOUR §1 (+x right, +y down, heading measured from +y, clockwise positive, unit
vector of heading θ = (-sin θ, cos θ)). Nothing here knows about pygame or pixels.

The hot paths (ultrasonic ray casting, collision tests, floor sampling) are compiled with
Numba: a sensor read must cost a few microseconds, which pure NumPy cannot do on arrays this
small (each NumPy call costs about a microsecond on its own). Maze walls lie on the cell grid,
so rays walk the grid cell by cell (Amanatides & Woo); a read therefore costs the same on a
4 x 8 maze as on a 40 x 80 one. Compiled code is cached on disk after the first run.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from simmer.pose import Pose as Pose  # noqa: PLC0414  (re-exported: plug-ins import it here)
from simmer.pose import Vec2 as Vec2  # noqa: PLC0414

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_EPS = 1e-12
_jit = numba.njit(cache=True, nogil=True, fastmath=False)
_inlined = numba.njit(cache=True, nogil=True, fastmath=False, inline="always")
"""For a kernel's parts that take arrays: a compiled call passes each array as a handful of
values, which costs a beam as much as its arithmetic; inlined (Numba's own pass), none."""


def polygon_gap(a: FloatArray, b: FloatArray) -> float:
    """Smallest distance between the outlines of two polygons (0 if their edges cross)."""
    best = math.inf
    for points, poly in ((a, b), (b, a)):  # every vertex of one against every edge of the other
        starts = poly
        edge = np.roll(poly, -1, axis=0) - starts
        length2 = np.maximum((edge**2).sum(axis=1), 1e-12)
        along = points[:, None, :] - starts[None, :, :]
        t = np.clip((along * edge).sum(axis=2) / length2, 0.0, 1.0)
        nearest = starts + t[:, :, None] * edge
        best = min(best, float(np.sqrt(((points[:, None, :] - nearest) ** 2).sum(axis=2)).min()))
    return best


def heading_vector(heading_deg: float) -> Vec2:
    """Unit vector of a heading: 0° points down (+y), 90° left (-x)."""
    rad = math.radians(heading_deg)
    return Vec2(-math.sin(rad), math.cos(rad))


def rotate(x: float, y: float, heading_deg: float) -> Vec2:
    """Rotate a robot-frame vector by ``heading_deg`` into the world frame."""
    rad = math.radians(heading_deg)
    c, s = math.cos(rad), math.sin(rad)
    return Vec2(x * c - y * s, x * s + y * c)


def wrap_degrees(angle: float) -> float:
    """Wrap an angle to [0, 360)."""
    wrapped = angle % 360.0
    return 0.0 if wrapped >= 360.0 else wrapped


def rectangle(width: float, length: float) -> FloatArray:
    """A centred rectangle outline (x extent ``width``, y extent ``length``) as (4, 2)."""
    hw, hl = width / 2.0, length / 2.0
    return np.array([[-hw, -hl], [-hw, hl], [hw, hl], [hw, -hl]], dtype=np.float64)


def disk_samples(count: int) -> FloatArray:
    """``count`` evenly spread points of the unit disk (a Vogel sunflower), shape (count, 2).

    Used to measure what fraction of a circle on the floor is white: each point stands for
    an equal share of the disk's area, so the fraction is exact to about 1/count.
    """
    golden = math.pi * (3.0 - math.sqrt(5.0))
    k = np.arange(count, dtype=np.float64)
    radius = np.sqrt((k + 0.5) / count)
    theta = k * golden
    return np.column_stack((radius * np.cos(theta), radius * np.sin(theta)))


# --------------------------------------------------------------------------- compiled kernels


@_jit
def _ray_segment(
    ox: float, oy: float, dx: float, dy: float, x1: float, y1: float, x2: float, y2: float
) -> float:
    """Distance along the unit ray (o, d) to segment (x1,y1)-(x2,y2), or inf if missed."""
    sx = x2 - x1
    sy = y2 - y1
    denom = dx * sy - dy * sx
    if abs(denom) < _EPS:
        return math.inf
    wx = x1 - ox
    wy = y1 - oy
    t = (wx * sy - wy * sx) / denom
    u = (wx * dy - wy * dx) / denom
    if t >= 0.0 and -_EPS <= u <= 1.0 + _EPS:
        return t
    return math.inf


@_jit
def ray_segments(ox: float, oy: float, dx: float, dy: float, segments: FloatArray) -> float:
    """Distance along a unit ray to the nearest of ``segments`` (N, 4: x1, y1, x2, y2)."""
    best = math.inf
    for i in range(segments.shape[0]):
        t = _ray_segment(
            ox, oy, dx, dy, segments[i, 0], segments[i, 1], segments[i, 2], segments[i, 3]
        )
        best = min(best, t)
    return best


@_jit
def _grid_axis(
    origin: float, direction: float, index: int, cell: float
) -> tuple[int, float, float]:
    """For one axis of a grid walk: the step (-1, 0, 1), the ray distance to the first grid line
    crossed, and the distance between successive lines."""
    if direction > _EPS:
        return 1, ((index + 1) * cell - origin) / direction, cell / direction
    if direction < -_EPS:
        return -1, (index * cell - origin) / direction, -cell / direction
    return 0, math.inf, math.inf


@_inlined
def _walk_grid(
    hwall: BoolArray,
    vwall: BoolArray,
    cx: int,
    cy: int,
    step_x: int,
    step_y: int,
    t_max_x: float,
    t_max_y: float,
    t_delta_x: float,
    t_delta_y: float,
    limit: float,
) -> float:
    """The grid walk (Amanatides & Woo) from cell (cx, cy), given each axis's step, distance
    to its first line and between lines: the distance to the first wall, inf if none is hit
    within ``limit``. The one walk, set up by :func:`ray_grid` (four divisions, the
    ultrasonic and ToF rays') and :func:`ray_grid_inverse` (one, the LiDAR's beams)."""
    rows = vwall.shape[0]
    cols = hwall.shape[1]
    while True:
        if t_max_x <= t_max_y:
            if t_max_x > limit:
                return math.inf
            line = cx + 1 if step_x > 0 else cx
            if vwall[cy, line]:
                return t_max_x
            cx += step_x
            if cx < 0 or cx >= cols:
                return math.inf
            t_max_x += t_delta_x
        else:
            if t_max_y > limit:
                return math.inf
            line = cy + 1 if step_y > 0 else cy
            if hwall[line, cx]:
                return t_max_y
            cy += step_y
            if cy < 0 or cy >= rows:
                return math.inf
            t_max_y += t_delta_y


@_jit
def ray_grid(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    ox: float,
    oy: float,
    dx: float,
    dy: float,
    limit: float,
) -> float:
    """Distance along a unit ray to the first grid wall, walking cell by cell.

    ``hwall[r, c]``: wall on the horizontal line y = r·cell over column c.
    ``vwall[r, c]``: wall on the vertical line x = c·cell over row r.
    Returns inf if nothing is hit within ``limit``, and -1 if the origin is outside the grid.
    The ultrasonic and ToF rays' walk (their released readings are its arithmetic's, to the
    last bit); :func:`ray_grid_inverse` sets the same walk up for the LiDAR.
    """
    rows = vwall.shape[0]
    cols = hwall.shape[1]
    cx = int(math.floor(ox / cell))
    cy = int(math.floor(oy / cell))
    if cx < 0 or cy < 0 or cx >= cols or cy >= rows:
        return -1.0
    step_x, t_max_x, t_delta_x = _grid_axis(ox, dx, cx, cell)
    step_y, t_max_y, t_delta_y = _grid_axis(oy, dy, cy, cell)
    return _walk_grid(
        hwall, vwall, cx, cy, step_x, step_y, t_max_x, t_max_y, t_delta_x, t_delta_y, limit
    )


@_inlined
def _grid_axis_inverse(
    origin: float, direction: float, inverse: float, index: int, cell: float
) -> tuple[int, float, float]:
    """:func:`_grid_axis` with the direction's reciprocal given: multiplications."""
    if direction > _EPS:
        return 1, ((index + 1) * cell - origin) * inverse, cell * inverse
    if direction < -_EPS:
        return -1, (index * cell - origin) * inverse, -cell * inverse
    return 0, math.inf, math.inf


@_inlined
def ray_grid_inverse(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    ox: float,
    oy: float,
    dx: float,
    dy: float,
    limit: float,
) -> float:
    """:func:`ray_grid`, its walk set up with one division, not four: 1/dx and 1/dy as dy and
    dx over dx·dy (within a few units in the last place of the quotients, so distances within
    1e-12 in of ray_grid's). The LiDAR's walk: its 360 beams a scan are most of a step's
    cost, and a division costs as much as the rest of a beam's setup."""
    rows = vwall.shape[0]
    cols = hwall.shape[1]
    per_cell = 1.0 / cell  # the same every beam: computed once a scan, out of the loop
    cx = int(math.floor(ox * per_cell))
    cy = int(math.floor(oy * per_cell))
    if cx < 0 or cy < 0 or cx >= cols or cy >= rows:
        return -1.0
    if abs(dx) > _EPS and abs(dy) > _EPS:
        r = 1.0 / (dx * dy)
        ix = dy * r
        iy = dx * r
    else:  # along an axis: the other's step is 0 and its reciprocal unused
        ix = 1.0 / dx if abs(dx) > _EPS else 0.0
        iy = 1.0 / dy if abs(dy) > _EPS else 0.0
    step_x, t_max_x, t_delta_x = _grid_axis_inverse(ox, dx, ix, cx, cell)
    step_y, t_max_y, t_delta_y = _grid_axis_inverse(oy, dy, iy, cy, cell)
    return _walk_grid(
        hwall, vwall, cx, cy, step_x, step_y, t_max_x, t_max_y, t_delta_x, t_delta_y, limit
    )


@_jit
def cast_fan(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block: FloatArray,
    see_block: bool,
    ox: float,
    oy: float,
    heading_deg: float,
    beamwidth_deg: float,
    max_range: float,
    out: FloatArray,
) -> float:
    """Cast ``len(out)`` rays of an ultrasonic fan; fill ``out`` with each ray's distance.

    Ray k of n leaves at ``((k - (n-1)/2) / n) · beamwidth`` from the heading (BEHAVIOUR §5.3).
    A ray that hits nothing within ``max_range`` gets inf. ``fallback`` (the wall segments)
    is used only when the origin lies outside the grid. Returns the shortest distance.
    """
    n = out.shape[0]
    best = math.inf
    for k in range(n):
        angle = math.radians(heading_deg + ((k - (n - 1) / 2.0) / n) * beamwidth_deg)
        dx = -math.sin(angle)
        dy = math.cos(angle)
        t = ray_grid(hwall, vwall, cell, ox, oy, dx, dy, max_range)
        if t < 0.0:
            t = ray_segments(ox, oy, dx, dy, fallback)
        if see_block:
            t = min(t, ray_segments(ox, oy, dx, dy, block))
        if t > max_range:
            t = math.inf
        out[k] = t
        best = min(best, t)
    return best


@_jit
def cast_fans(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block: FloatArray,
    rx: float,
    ry: float,
    rheading: float,
    bx: float,
    by: float,
    side: float,
    mounts: FloatArray,
    out: FloatArray,
    only: int,
) -> None:
    """Cast the fans of several ultrasonic sensors on a robot at (``rx``, ``ry``, ``rheading``)
    in one call: a Python call per fan costs more than its rays. ``only``: that sensor's fan
    alone (-1: every one).

    ``bx``, ``by``, ``side``: the block's centre and side. ``mounts`` (K, 7), a sensor a
    row: its x, y and rotation on the robot, its height (NaN: the block's side), beamwidth,
    max_range and rays.
    Fills ``out[k]``: the sensor's x, y and heading in the world, the fan's shortest
    distance, then its rays' (:func:`cast_fan`). The arithmetic is
    :meth:`~simmer.devices.base.Device.world_pose`'s and the block test BEHAVIOUR §5.3's, in
    the same order, so the readings are those of a fan cast on its own."""
    rad = math.radians(rheading)
    c = math.cos(rad)
    s = math.sin(rad)
    for k in range(mounts.shape[0]):
        if only >= 0 and k != only:
            continue
        px, py, rotation, height = mounts[k, 0], mounts[k, 1], mounts[k, 2], mounts[k, 3]
        beamwidth, max_range, n = mounts[k, 4], mounts[k, 5], int(mounts[k, 6])
        x = rx + px * c - py * s
        y = ry + px * s + py * c
        heading = rheading + rotation
        h = (side if math.isnan(height) else height) - side
        d = math.hypot(bx - x, by - y)
        sees = math.degrees(math.atan2(h, d)) <= beamwidth / 2.0
        out[k, 0] = x
        out[k, 1] = y
        out[k, 2] = heading
        out[k, 3] = cast_fan(
            hwall,
            vwall,
            cell,
            fallback,
            block,
            sees,
            x,
            y,
            heading,
            beamwidth,
            max_range,
            out[k, 4 : 4 + n],
        )


@_jit
def _within(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> bool:
    """True if (px, py) lies in the bounding box of segment AB (for collinear points)."""
    return (min(ax, bx) - _EPS <= px <= max(ax, bx) + _EPS) and (
        min(ay, by) - _EPS <= py <= max(ay, by) + _EPS
    )


@_jit
def _segments_cross(
    ax: float, ay: float, bx: float, by: float, cx: float, cy: float, dx: float, dy: float
) -> bool:
    """True if closed segments AB and CD touch or cross."""
    d1 = (dx - cx) * (ay - cy) - (dy - cy) * (ax - cx)
    d2 = (dx - cx) * (by - cy) - (dy - cy) * (bx - cx)
    d3 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    d4 = (bx - ax) * (dy - ay) - (by - ay) * (dx - ax)
    if ((d1 > 0 and d2 < 0) or (d1 < 0 and d2 > 0)) and (
        (d3 > 0 and d4 < 0) or (d3 < 0 and d4 > 0)
    ):
        return True
    return (
        (abs(d1) <= _EPS and _within(ax, ay, cx, cy, dx, dy))
        or (abs(d2) <= _EPS and _within(bx, by, cx, cy, dx, dy))
        or (abs(d3) <= _EPS and _within(cx, cy, ax, ay, bx, by))
        or (abs(d4) <= _EPS and _within(dx, dy, ax, ay, bx, by))
    )


@_jit
def point_in_polygon(px: float, py: float, poly: FloatArray) -> bool:
    """Even-odd test: is (px, py) strictly inside polygon ``poly`` (K, 2)?"""
    inside = False
    k = poly.shape[0]
    j = k - 1
    for i in range(k):
        xi, yi = poly[i, 0], poly[i, 1]
        xj, yj = poly[j, 0], poly[j, 1]
        if (yi > py) != (yj > py):
            x_cross = xi + (py - yi) * (xj - xi) / (yj - yi)
            if px < x_cross:
                inside = not inside
        j = i
    return inside


@_jit
def place_polygon(
    local: FloatArray, x: float, y: float, heading_deg: float, out: FloatArray
) -> None:
    """Write ``local`` (K, 2, robot frame) placed at pose (x, y, heading) into ``out``."""
    rad = math.radians(heading_deg)
    c = math.cos(rad)
    s = math.sin(rad)
    for i in range(local.shape[0]):
        px = local[i, 0]
        py = local[i, 1]
        out[i, 0] = x + px * c - py * s
        out[i, 1] = y + px * s + py * c


@_jit
def _edge_hits_segment(poly: FloatArray, x1: float, y1: float, x2: float, y2: float) -> bool:
    k = poly.shape[0]
    for i in range(k):
        j = (i + 1) % k
        if _segments_cross(poly[i, 0], poly[i, 1], poly[j, 0], poly[j, 1], x1, y1, x2, y2):
            return True
    return point_in_polygon(0.5 * (x1 + x2), 0.5 * (y1 + y2), poly)


@_jit
def polygons_overlap(a: FloatArray, b: FloatArray) -> bool:
    """True if polygons ``a`` and ``b`` touch, cross or one contains the other."""
    kb = b.shape[0]
    for i in range(kb):
        j = (i + 1) % kb
        if _edge_hits_segment(a, b[i, 0], b[i, 1], b[j, 0], b[j, 1]):
            return True
    return point_in_polygon(a[0, 0], a[0, 1], b) or point_in_polygon(b[0, 0], b[0, 1], a)


@_jit
def polygon_hits_grid(
    poly: FloatArray, hwall: BoolArray, vwall: BoolArray, solid: BoolArray, cell: float
) -> bool:
    """True if polygon ``poly`` (world frame) touches a grid wall or lies in a solid cell.

    Only the grid lines under the polygon's bounding box are examined, so the cost does not
    grow with the maze. A vertex outside the maze or inside a solid cell counts as a hit.
    """
    rows = solid.shape[0]
    cols = solid.shape[1]
    min_x = poly[:, 0].min()
    max_x = poly[:, 0].max()
    min_y = poly[:, 1].min()
    max_y = poly[:, 1].max()
    for i in range(poly.shape[0]):
        cx = int(math.floor(poly[i, 0] / cell))
        cy = int(math.floor(poly[i, 1] / cell))
        if cx < 0 or cy < 0 or cx >= cols or cy >= rows or solid[cy, cx]:
            return True
    c0 = max(int(math.floor(min_x / cell)), 0)
    c1 = min(int(math.floor(max_x / cell)), cols - 1)
    r0 = max(int(math.floor(min_y / cell)), 0)
    r1 = min(int(math.floor(max_y / cell)), rows - 1)
    for r in range(r0, r1 + 2):
        if r > rows:
            break
        y = r * cell
        if y < min_y - _EPS or y > max_y + _EPS:
            continue
        for c in range(c0, c1 + 1):
            if hwall[r, c] and _edge_hits_segment(poly, c * cell, y, (c + 1) * cell, y):
                return True
    for c in range(c0, c1 + 2):
        if c > cols:
            break
        x = c * cell
        if x < min_x - _EPS or x > max_x + _EPS:
            continue
        for r in range(r0, r1 + 1):
            if vwall[r, c] and _edge_hits_segment(poly, x, r * cell, x, (r + 1) * cell):
                return True
    return False


@_jit
def white_fraction(
    floor_white: BoolArray, tile: float, cx: float, cy: float, radius: float, samples: FloatArray
) -> float:
    """Fraction of the floor disk (centre (cx, cy), ``radius``) that is white.

    ``floor_white`` is indexed [row, column]; points off the floor count as black.
    """
    rows = floor_white.shape[0]
    cols = floor_white.shape[1]
    white = 0
    n = samples.shape[0]
    for i in range(n):
        ix = int(math.floor((cx + radius * samples[i, 0]) / tile))
        iy = int(math.floor((cy + radius * samples[i, 1]) / tile))
        if 0 <= ix < cols and 0 <= iy < rows and floor_white[iy, ix]:
            white += 1
    return float(white) / float(n)


@_jit
def robot_blocked(
    local: FloatArray,
    x: float,
    y: float,
    heading_deg: float,
    scratch: FloatArray,
    hwall: BoolArray,
    vwall: BoolArray,
    solid: BoolArray,
    cell: float,
    block: FloatArray,
) -> bool:
    """True if the outline ``local`` placed at (x, y, heading) touches a wall or the block.

    ``scratch`` (same shape as ``local``) receives the placed outline.
    """
    place_polygon(local, x, y, heading_deg, scratch)
    if polygon_hits_grid(scratch, hwall, vwall, solid, cell):
        return True
    return polygons_overlap(scratch, block)


@_inlined
def lidar_beam(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block: FloatArray,
    see_block: bool,
    ox: float,
    oy: float,
    dx: float,
    dy: float,
    max_range: float,
) -> float:
    """Distance along one LiDAR beam, the unit vector (dx, dy), to the first wall, or the block
    if ``see_block``; inf if nothing is hit within ``max_range``. ``fallback`` (the wall
    segments) is used only when the origin lies outside the grid. A scan's beams and
    ``Simulation.expected``'s both: the same arithmetic, the same readings."""
    t = ray_grid_inverse(hwall, vwall, cell, ox, oy, dx, dy, max_range)
    if t < 0.0:
        t = ray_segments(ox, oy, dx, dy, fallback)
    if see_block:
        t = min(t, ray_segments(ox, oy, dx, dy, block))
    if t > max_range:
        return math.inf
    return t


@_jit
def _turned(c: float, s: float, e: float) -> tuple[float, float]:
    """(c, s) turned by a small angle ``e`` radians: a beam's angular jitter. Within 0.01 rad
    the series to e^5 (error below 2e-15), so no sine and cosine a beam; beyond them exactly."""
    if -0.01 < e < 0.01:
        e2 = e * e
        ce = 1.0 - e2 * (0.5 - e2 * (1.0 / 24.0))
        se = e * (1.0 - e2 * (1.0 / 6.0 - e2 * (1.0 / 120.0)))
    else:
        ce = math.cos(e)
        se = math.sin(e)
    return ce * c - se * s, se * c + ce * s


@_jit
def scan_revolution(
    hwall: BoolArray,
    vwall: BoolArray,
    fallback: FloatArray,
    block: FloatArray,
    track: FloatArray,
    state: FloatArray,
    vectors: FloatArray,
    normals: FloatArray,
    gaps: FloatArray,
    distances: FloatArray,
    points: FloatArray,
) -> int:
    """One LiDAR revolution, whole: beam k of n is measured at ``start + k · (period / n)``
    (``start``: ``end - period``; skew; else all at ``end``), from the robot pose then,
    interpolated along ``track`` (flat: time, x, y, heading in [0, 360), time, ...; the
    headings are unwrapped here, in place, and a beam's heading is the last pose's plus the
    turn since then, so it is exact while the robot stands still); the beam is cast
    (:func:`lidar_beam`) from the device mounted at (px, py) in the robot frame along its
    ``vectors`` column (2, n: each beam's unit vector at heading 0, the mount's rotation
    included) turned by the pose's heading, then its noise. ``state``: cell, see_block,
    period, end, skew, px, py, min_range, max_range, range_error, range_error_proportional,
    dropout, angular_jitter (radians), where this revolution's standard normals start in
    ``normals``, the jitter's and the range error's (-1: that noise is off; both moved on to
    the next revolution's), and the dropout's place in ``gaps`` (the beams from one dropped
    beam to the next, geometric draws): the next gap's index (-1: no dropout) and the beams
    to pass before the next dropped one, both updated. Fills ``distances`` (0: no return) and
    ``points`` (where each beam met something, NaN where it returned nothing); returns the
    index of the last pose at or before ``end`` (the poses before it are no longer needed).

    Speed (a 360-beam scan is some microseconds, most of it memory the steps between scans
    have pushed out of the cache): one pass over the beams that writes only the readings; one
    sine and cosine a pose heading (a robot not turning has one heading all revolution), none
    a beam (its vector is turned; its jitter by a series); a division a step of the track, not
    a beam; a draw a dropped beam (not a uniform a beam); one compiled call a scan."""
    cell, see_block, period = state[0], state[1] != 0.0, state[2]
    end, skew = state[3], state[4] != 0.0
    start = end - period
    px, py, low, high = state[5], state[6], state[7], state[8]
    const, prop, jitter = state[9], state[10], state[12]
    jn, rn, gap, left = int(state[13]), int(state[14]), int(state[15]), state[16]
    n = distances.shape[0]
    m = track.shape[0] // 4
    heading_now = track[4 * m - 1]
    last = track[3]
    for i in range(7, 4 * m, 4):  # unwrapped: each within a half turn of the one before
        h = track[i]
        if not -180.0 < last - h < 180.0:
            h += 360.0 * round((last - h) / 360.0)
            track[i] = h
        last = h
    spacing = period / n  # seconds from one beam to the next
    j = 0
    span = -1  # the step whose 1 / duration ``inverse`` is
    inverse = 0.0
    heading = math.nan
    c = s = 0.0
    for k in range(n):
        t = start + k * spacing if skew else end
        while j + 1 < m and track[4 * j + 4] < t:
            j += 1
        if t <= track[0] or m == 1:
            x, y, turn = track[1], track[2], track[3] - last
        elif j + 1 >= m:
            x, y, turn = track[4 * m - 3], track[4 * m - 2], 0.0
        else:
            i = 4 * j
            if span != j:
                span = j
                inverse = 1.0 / (track[i + 4] - track[i])
            f = (t - track[i]) * inverse
            x = track[i + 1] + f * (track[i + 5] - track[i + 1])
            y = track[i + 2] + f * (track[i + 6] - track[i + 2])
            a = track[i + 3] - last
            turn = a + f * ((track[i + 7] - last) - a)
        rh = heading_now + turn
        if rh != heading:
            heading = rh
            rad = math.radians(rh)
            c = math.cos(rad)
            s = math.sin(rad)
        ox = x + px * c - py * s
        oy = y + px * s + py * c
        ex, ey = vectors[0, k], vectors[1, k]
        dx = c * ex - s * ey
        dy = s * ex + c * ey
        if jn >= 0:
            dx, dy = _turned(dx, dy, jitter * normals[jn + k])
        d = lidar_beam(hwall, vwall, cell, fallback, block, see_block, ox, oy, dx, dy, high)
        if d != math.inf and rn >= 0:
            d = d + (const + prop * d) * normals[rn + k]
        dropped = False
        if gap >= 0:  # one draw a dropped beam, not one a beam
            if left == 0.0:
                dropped = True
                left = gaps[gap] - 1.0
                gap += 1
            else:
                left -= 1.0
        if d == math.inf or d < low or d > high or dropped:
            distances[k] = 0.0
            points[k, 0] = math.nan
            points[k, 1] = math.nan
        else:
            distances[k] = d
            points[k, 0] = ox + dx * d
            points[k, 1] = oy + dy * d
    if gap >= 0:
        state[15] = gap
        state[16] = left
    rows = (jn >= 0) + (rn >= 0)  # the next revolution's normals
    if jn >= 0:
        state[13] = jn + rows * n
    if rn >= 0:
        state[14] = rn + rows * n
    kept = 0
    while kept + 1 < m and track[4 * kept + 4] <= end:
        kept += 1
    return kept
