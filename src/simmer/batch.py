"""Many robots in one maze, stepped in one compiled call: for policy search, tuning and
particle filters.

:class:`Batch` holds N robots of one configuration, each with its own seed (no robot-robot
contact: each sees the maze and its own block). One call of :meth:`Batch.step` advances every
robot by whole simulation steps: a drive command where one is given, each drive's motion with
its bias and error, the walls and the block stopping it, and the ultrasonic sensors the run
reads every step (``simulate_list``), with noise. Robot i reproduces exactly what a single
:class:`simmer.Simulation` seeded with ``seeds[i]`` does for the same commands: its noise
comes from the same streams (``Simulation.stream``), drawn in blocks but consumed in the same
order, and the arithmetic is the same double-precision arithmetic (docs/gym.md).

:class:`Model` is the plain NumPy motion and sensor model a particle filter needs: move N
poses by a drive command under the drive's noise, and read N poses' sensors with noise or
without (``expected``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
from numpy.typing import NDArray

from simmer.config.loader import as_config, load_config
from simmer.config.maze import Block, Maze, robot_outline
from simmer.config.models import SimConfig
from simmer.config.scenario import draw_scenario
from simmer.config.zones import Zones
from simmer.devices import Drive, DriveParams, UltrasonicParams
from simmer.errors import BatchError
from simmer.geometry import (
    FloatArray,
    place_polygon,
    polygon_hits_grid,
    polygons_overlap,
    ray_grid,
    ray_segments,
)
from simmer.world.simulation import source_stream

__all__ = ["Batch", "BatchError", "Model"]

IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

NOISE_BLOCK = 256
"""Noise values drawn at once from each robot's stream of each noisy device (per refill)."""
MAX_ROBOTS = 1_000_000
"""The most robots one batch holds (``batch_robots`` in docs/limits.md)."""

FREE_SPACING = 0.5
"""Inches between the outline's points that the free-space shortcut checks."""
FIELD_CELL = 48
"""Wall-distance lattice nodes per cell side (fewer in a maze so large it would pass
``FIELD_NODES``): finer lets a robot closer to a wall skip its collision test."""
FIELD_NODES = 1_000_000
"""The most nodes the wall-distance lattice has (8 MB)."""
_MARGIN = 1e-6
"""Inches: the clearance a free-space shortcut keeps besides its bounds (rounding is ~1e-14)."""

_jit = numba.njit(cache=True, nogil=True, fastmath=False)
_MAX_THREADS: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]


# --------------------------------------------------------------------------- compiled step


@_jit
def _draw(noise: FloatArray, cursor: IntArray, i: int, channel: int) -> float:
    """The next N(0, 2) value of robot i's stream for ``channel``."""
    k = cursor[i, channel]
    cursor[i, channel] = k + 1
    return float(noise[i, channel, k])


@_jit
def _fan(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block: FloatArray,
    see_block: bool,
    bx: float,
    by: float,
    reach: float,
    ox: float,
    oy: float,
    heading_deg: float,
    beamwidth_deg: float,
    max_range: float,
    out: FloatArray,
) -> float:
    """``geometry.cast_fan``, the same arithmetic, but a ray tests the block's edges only if
    it passes within ``reach`` of the block's centre (bx, by) before its wall: a ray that
    cannot touch the block gets the same distance without the four edge tests."""
    n = out.shape[0]
    best = math.inf
    wx = bx - ox
    wy = by - oy
    w2 = wx * wx + wy * wy
    for k in range(n):
        angle = math.radians(heading_deg + ((k - (n - 1) / 2.0) / n) * beamwidth_deg)
        dx = -math.sin(angle)
        dy = math.cos(angle)
        t = ray_grid(hwall, vwall, cell, ox, oy, dx, dy, max_range)
        if t < 0.0:
            t = ray_segments(ox, oy, dx, dy, fallback)
        if see_block:
            along = wx * dx + wy * dy
            if along >= -reach and along - reach <= t and w2 - along * along <= reach * reach:
                t = min(t, ray_segments(ox, oy, dx, dy, block))
        if t > max_range:
            t = math.inf
        out[k] = t
        best = min(best, t)
    return best


@_jit
def _read_sensors(
    i: int,
    x: float,
    y: float,
    heading: float,
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block_seg: FloatArray,
    block_xy: FloatArray,
    block_size: FloatArray,
    sensors: FloatArray,
    sensor_rays: IntArray,
    sensor_channel: IntArray,
    rays: FloatArray,
    noise: FloatArray,
    cursor: IntArray,
    readings: FloatArray,
) -> None:
    """Read every sensor of robot i at (x, y, heading) as ``Ultrasonic.simulate`` does.

    ``sensors[s]``: position x, y, rotation, beamwidth, min_range, max_range, error, height
    (NaN: the block's size). A channel of -1 draws no noise (noise-free, ``expected``)."""
    rad = math.radians(heading)
    c = math.cos(rad)
    s = math.sin(rad)
    size = block_size[i]
    reach = size * 0.7072 + 1e-6  # the block's half diagonal, and a margin
    for k in range(sensors.shape[0]):
        px = sensors[k, 0]
        py = sensors[k, 1]
        sx = x + px * c - py * s
        sy = y + px * s + py * c
        sh = heading + sensors[k, 2]
        beam = sensors[k, 3]
        height = sensors[k, 7]
        if math.isnan(height):
            height = size
        h = height - size
        d = math.hypot(block_xy[i, 0] - sx, block_xy[i, 1] - sy)
        sees = math.degrees(math.atan2(h, d)) <= beam / 2.0
        min_range = sensors[k, 4]
        max_range = sensors[k, 5]
        error = sensors[k, 6]
        distance = _fan(
            hwall,
            vwall,
            cell,
            fallback,
            block_seg[i],
            sees,
            block_xy[i, 0],
            block_xy[i, 1],
            reach,
            sx,
            sy,
            sh,
            beam,
            max_range,
            rays[: sensor_rays[k]],
        )
        if distance == math.inf:
            reading = max_range
        else:
            channel = sensor_channel[k]
            if channel >= 0 and error != 0.0 and distance != 0.0:
                distance = distance + _draw(noise, cursor, i, channel) * error * distance
            reading = min(max(distance, min_range), max_range)
        readings[i, k] = reading


@_jit
def _wall_field(
    hwall: BoolArray, vwall: BoolArray, solid: BoolArray, cell: float, step: float
) -> FloatArray:
    """The distance from each node of a square lattice (``step`` apart, from the maze's
    corner) to the nearest grid wall, solid cell or the outside of the grid, capped at
    ``cell``: what ``robot_blocked`` tests against, so a polygon farther than this from every
    node's obstacles cannot touch one. Only the 3 x 3 cells around a node can be nearer."""
    rows = solid.shape[0]
    cols = solid.shape[1]
    width = cols * cell
    height = rows * cell
    nx = int(math.floor(width / step)) + 1
    ny = int(math.floor(height / step)) + 1
    out = np.empty((ny, nx))
    for j in range(ny):
        y = j * step
        r = min(int(math.floor(y / cell)), rows - 1)
        for i in range(nx):
            x = i * step
            c = min(int(math.floor(x / cell)), cols - 1)
            best = min(cell, x, y, width - x, height - y)
            for rr in range(max(r - 1, 0), min(r + 3, rows + 1)):
                for cc in range(max(c - 1, 0), min(c + 2, cols)):
                    if hwall[rr, cc]:
                        gx = min(max(x, cc * cell), (cc + 1) * cell)
                        best = min(best, math.hypot(x - gx, y - rr * cell))
            for rr in range(max(r - 1, 0), min(r + 2, rows)):
                for cc in range(max(c - 1, 0), min(c + 3, cols + 1)):
                    if vwall[rr, cc]:
                        gy = min(max(y, rr * cell), (rr + 1) * cell)
                        best = min(best, math.hypot(x - cc * cell, y - gy))
            for rr in range(max(r - 1, 0), min(r + 2, rows)):
                for cc in range(max(c - 1, 0), min(c + 2, cols)):
                    if solid[rr, cc]:
                        gx = min(max(x, cc * cell), (cc + 1) * cell)
                        gy = min(max(y, rr * cell), (rr + 1) * cell)
                        best = min(best, math.hypot(x - gx, y - gy))
            out[j, i] = best
    return out


@_jit
def _clearance(
    samples: FloatArray,
    loss: float,
    x: float,
    y: float,
    heading: float,
    field: FloatArray,
    step: float,
    bx: float,
    by: float,
    block_radius: float,
    radius: float,
) -> float:
    """A lower bound on how far the outline placed at (x, y, heading) is from every wall,
    solid cell, the outside and the block (less a margin): > 0 means ``robot_blocked`` is
    False there, and stays False while the outline moves less than this.

    ``samples``: points along the outline's edges, at most 2 ``loss`` apart. A lattice node
    is within ``step`` / sqrt(2) of a sample, and distance changes no faster than position."""
    if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(heading)):
        return -1.0  # no look-up for a pose that is nowhere
    rad = math.radians(heading)
    c = math.cos(rad)
    s = math.sin(rad)
    ny = field.shape[0]
    nx = field.shape[1]
    lost = loss + step * 0.70711 + _MARGIN
    best = math.hypot(x - bx, y - by) - radius - block_radius - _MARGIN
    for k in range(samples.shape[0]):
        px = samples[k, 0]
        py = samples[k, 1]
        i = int(math.floor((x + px * c - py * s) / step + 0.5))
        j = int(math.floor((y + px * s + py * c) / step + 0.5))
        if i < 0 or j < 0 or i >= nx or j >= ny:
            return -1.0
        best = min(best, field[j, i] - lost)
        if best <= 0.0:
            break  # not clear: how far in does not matter
    return best


_MEMO_START = np.array([-1.0, 0.0, 0.0, 0.0, math.nan, math.nan, math.nan, 0.0, 0.0])
"""A robot's ``_collides`` memo before its first step: no clearance known (budget, where,
where it was), no pose tested (pose, answer), no cool-down."""
_COOL_DOWN = 8
"""Steps a robot near a wall is tested outright before its clearance is computed again."""


@_jit
def _known(memo: FloatArray, x: float, y: float, heading: float, radius: float) -> int:
    """What ``memo`` already tells of the outline at (x, y, heading): 1 blocked (the pose last
    tested, which was), 0 free (the pose last tested, or the outline moved less than its
    clearance ``memo[0]`` since that was computed at ``memo[1:4]``: no point of it moved farther
    than the centre did plus ``radius`` times the turn), -1 not known. Kept apart from
    :func:`_collides` so the common case costs no call with many arrays."""
    if x == memo[4] and y == memo[5] and heading == memo[6]:
        return 1 if memo[7] != 0.0 else 0
    turned = 0.0  # radians between this heading and memo[3], the short way
    if heading != memo[3]:
        d = abs(heading - memo[3]) % 360.0
        turned = math.radians(min(d, 360.0 - d))
    left = memo[0] - radius * turned
    if left > 0.0 and (x - memo[1]) ** 2 + (y - memo[2]) ** 2 < left * left:
        return 0
    return -1


@_jit
def _collides(
    memo: FloatArray,
    x: float,
    y: float,
    heading: float,
    outline: FloatArray,
    scratch: FloatArray,
    free: FloatArray,
    free_loss: float,
    field: FloatArray,
    field_step: float,
    radius: float,
    hwall: BoolArray,
    vwall: BoolArray,
    solid: BoolArray,
    cell: float,
    block_poly: FloatArray,
    bx: float,
    by: float,
    block_radius: float,
) -> bool:
    """``geometry.robot_blocked`` for the outline at (x, y, heading) where :func:`_known` does
    not know, the same answer at a fraction of the cost: the clearance (:func:`_clearance`,
    from ``free`` points along the outline and the wall ``field``; none: no shortcut) computed
    and remembered, and if it is not positive the test, with the block's polygons left out
    where the two cannot meet. ``memo``: clearance, x, y, heading where computed, the last pose
    tested, its answer, steps of cool-down left (a robot near a wall is tested outright a
    while before its clearance is computed again)."""
    if free.shape[0] > 0:
        if memo[8] > 0.0:
            memo[8] -= 1.0
        else:
            budget = _clearance(
                free, free_loss, x, y, heading, field, field_step, bx, by, block_radius, radius
            )
            memo[0] = budget
            memo[1] = x
            memo[2] = y
            memo[3] = heading
            if budget > 0.0:
                return False
            memo[8] = _COOL_DOWN
    place_polygon(outline, x, y, heading, scratch)
    blocked = polygon_hits_grid(scratch, hwall, vwall, solid, cell) or (
        math.hypot(x - bx, y - by) <= radius + block_radius + _MARGIN
        and polygons_overlap(scratch, block_poly)
    )
    memo[4] = x
    memo[5] = y
    memo[6] = heading
    memo[7] = 1.0 if blocked else 0.0
    return blocked


@_jit
def _wrap(angle: float) -> float:
    """``geometry.wrap_degrees``: to [0, 360)."""
    wrapped = angle % 360.0
    return 0.0 if wrapped >= 360.0 else wrapped


@_jit
def _robot(
    i: int,
    steps: int,
    dt: float,
    pose: FloatArray,
    remaining: FloatArray,
    was_blocked: BoolArray,
    collisions: IntArray,
    blocked_steps: IntArray,
    command_drive: IntArray,
    command_value: FloatArray,
    replies: FloatArray,
    drives: FloatArray,
    drive_channel: IntArray,
    bias: FloatArray,
    outline: FloatArray,
    scratch: FloatArray,
    memo: FloatArray,
    free: FloatArray,
    free_loss: float,
    field: FloatArray,
    field_step: float,
    radius: float,
    hwall: BoolArray,
    vwall: BoolArray,
    solid: BoolArray,
    cell: float,
    fallback: FloatArray,
    block_poly: FloatArray,
    block_seg: FloatArray,
    block_xy: FloatArray,
    block_size: FloatArray,
    sensors: FloatArray,
    sensor_rays: IntArray,
    sensor_channel: IntArray,
    rays: FloatArray,
    noise: FloatArray,
    cursor: IntArray,
    readings: FloatArray,
) -> None:
    """Robot i: its command (if any), then ``steps`` simulation steps, as
    ``Simulation.execute`` and ``Simulation._step_once`` do them.

    ``drives[d]``: unit x, unit y, turn, speed, error total. ``memo``: :func:`_collides`'s
    (reset here); ``free``, ``field`` and ``radius`` as it takes them."""
    n_drives = drives.shape[0]
    memo[:] = _MEMO_START
    block_radius = 0.0  # the block's farthest corner from its centre
    for v in range(block_poly.shape[1]):
        block_radius = max(
            block_radius,
            math.hypot(block_poly[i, v, 0] - block_xy[i, 0], block_poly[i, v, 1] - block_xy[i, 1]),
        )
    trig_heading = wrap_in = wrap_out = math.nan
    c = s = 0.0
    d = command_drive[i]
    if d >= 0:
        moving = False
        for e in range(n_drives):
            if remaining[i, e] != 0.0:
                moving = True
        if moving:
            replies[i] = math.nan
        else:
            value = command_value[i]
            error = drives[d, 4]
            if error != 0.0 and value != 0.0:
                value = value + _draw(noise, cursor, i, drive_channel[d]) * error * value
            remaining[i, d] = value
            replies[i] = math.inf
    for _ in range(steps):
        dx = 0.0
        dy = 0.0
        rotation = 0.0
        moved = False
        for e in range(n_drives):
            left = remaining[i, e]
            if left != 0.0:
                limit = drives[e, 3] * dt
                step = math.copysign(min(abs(left), limit), left)
                left -= step
                if abs(left) < 1e-12:
                    left = 0.0
                remaining[i, e] = left
                dx += (drives[e, 0] + bias[i, e, 0]) * step
                dy += (drives[e, 1] + bias[i, e, 1]) * step
                rotation += (drives[e, 2] + bias[i, e, 2]) * step
                moved = True
        if moved:
            x = pose[i, 0]
            y = pose[i, 1]
            heading = pose[i, 2]
            if heading != trig_heading:  # a straight drive keeps its heading: same cos, sin
                rad = math.radians(heading)
                c = math.cos(rad)
                s = math.sin(rad)
                trig_heading = heading
            tx = x + (dx * c - dy * s)
            ty = y + (dx * s + dy * c)
            turned = heading + rotation
            if turned != wrap_in:  # the same sum wraps to the same heading
                wrap_in = turned
                wrap_out = _wrap(turned)
            th = wrap_out
            known = _known(memo, tx, ty, th, radius)
            blocked = (
                known == 1
                if known >= 0
                else _collides(
                    memo,
                    tx,
                    ty,
                    th,
                    outline,
                    scratch,
                    free,
                    free_loss,
                    field,
                    field_step,
                    radius,
                    hwall,
                    vwall,
                    solid,
                    cell,
                    block_poly[i],
                    block_xy[i, 0],
                    block_xy[i, 1],
                    block_radius,
                )
            )
            if blocked:
                blocked_steps[i] += 1
                if not was_blocked[i]:
                    collisions[i] += 1
                    was_blocked[i] = True
            else:
                was_blocked[i] = False
                pose[i, 0] = tx
                pose[i, 1] = ty
                pose[i, 2] = th
        if sensors.shape[0] == 0:
            if moved:
                continue
            break  # nothing moves and nothing is read: the other steps change nothing
        _read_sensors(
            i,
            pose[i, 0],
            pose[i, 1],
            pose[i, 2],
            hwall,
            vwall,
            cell,
            fallback,
            block_seg,
            block_xy,
            block_size,
            sensors,
            sensor_rays,
            sensor_channel,
            rays,
            noise,
            cursor,
            readings,
        )


def _step_all(
    steps: int,
    dt: float,
    pose: FloatArray,
    remaining: FloatArray,
    was_blocked: BoolArray,
    collisions: IntArray,
    blocked_steps: IntArray,
    command_drive: IntArray,
    command_value: FloatArray,
    replies: FloatArray,
    drives: FloatArray,
    drive_channel: IntArray,
    bias: FloatArray,
    outline: FloatArray,
    free: FloatArray,
    free_loss: float,
    field: FloatArray,
    field_step: float,
    radius: float,
    hwall: BoolArray,
    vwall: BoolArray,
    solid: BoolArray,
    cell: float,
    fallback: FloatArray,
    block_poly: FloatArray,
    block_seg: FloatArray,
    block_xy: FloatArray,
    block_size: FloatArray,
    sensors: FloatArray,
    sensor_rays: IntArray,
    sensor_channel: IntArray,
    noise: FloatArray,
    cursor: IntArray,
    readings: FloatArray,
    active: BoolArray,
    chunks: int,
) -> None:
    """Every active robot, in ``chunks`` runs of robots (each with its own scratch arrays;
    compiled with ``parallel=True`` the chunks run on Numba's threads)."""
    n = pose.shape[0]
    max_rays = 1
    for k in range(sensor_rays.shape[0]):
        max_rays = max(max_rays, sensor_rays[k])
    for chunk in numba.prange(chunks):
        scratch = np.empty_like(outline)
        memo = np.empty(len(_MEMO_START))
        rays = np.empty(max_rays)
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            if not active[i]:
                continue
            _robot(
                i,
                steps,
                dt,
                pose,
                remaining,
                was_blocked,
                collisions,
                blocked_steps,
                command_drive,
                command_value,
                replies,
                drives,
                drive_channel,
                bias,
                outline,
                scratch,
                memo,
                free,
                free_loss,
                field,
                field_step,
                radius,
                hwall,
                vwall,
                solid,
                cell,
                fallback,
                block_poly,
                block_seg,
                block_xy,
                block_size,
                sensors,
                sensor_rays,
                sensor_channel,
                rays,
                noise,
                cursor,
                readings,
            )


_step = _jit(_step_all)
_step_parallel = numba.njit(cache=False, nogil=True, fastmath=False, parallel=True)(_step_all)


@_jit
def _sense(
    pose: FloatArray,
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block_seg: FloatArray,
    block_xy: FloatArray,
    block_size: FloatArray,
    sensors: FloatArray,
    sensor_rays: IntArray,
    sensor_channel: IntArray,
    rays: FloatArray,
    noise: FloatArray,
    readings: FloatArray,
) -> None:
    """Read every sensor at each of the poses (one block for all), noise from ``noise``."""
    cursor = np.zeros((pose.shape[0], noise.shape[1]), dtype=np.int64)
    for i in range(pose.shape[0]):
        _read_sensors(
            i,
            pose[i, 0],
            pose[i, 1],
            pose[i, 2],
            hwall,
            vwall,
            cell,
            fallback,
            block_seg,
            block_xy,
            block_size,
            sensors,
            sensor_rays,
            sensor_channel,
            rays,
            noise,
            cursor,
            readings,
        )


# --------------------------------------------------------------------------- the layout


@dataclass(frozen=True)
class _Layout:
    """What a configuration gives every robot alike: maze, outline, drives and sensors."""

    config: SimConfig
    maze: Maze
    zones: Zones
    dt: float
    outline: FloatArray
    drive_ids: tuple[str, ...]
    drives: FloatArray
    sensor_ids: tuple[str, ...]
    sensors: FloatArray
    sensor_rays: IntArray
    channels: tuple[str, ...]
    """The devices whose noise a step draws, in channel order: noisy drives, then sensors."""
    drive_channel: IntArray
    sensor_channel: IntArray
    free: FloatArray
    """Points along the outline for the free-space shortcut (none: every step is tested)."""
    free_loss: float
    field: FloatArray
    field_step: float
    radius: float

    @classmethod
    def of(cls, config: SimConfig, sensors: Sequence[str] | None) -> _Layout:
        settings = config.settings
        specs = {spec.id: spec for spec in config.devices}
        drive_ids, drive_rows = [], []
        for spec in config.devices:
            if isinstance(spec.params, DriveParams):
                drive = Drive(spec.id, spec.params, np.random.default_rng(0))
                error = spec.params.error
                total = drive.unit[0] * error.x + drive.unit[1] * error.y
                total += drive.turn * error.rotation
                drive_ids.append(spec.id)
                drive_rows.append((drive.unit[0], drive.unit[1], drive.turn, drive.speed, total))
        if sensors is None:
            listed = [name for name in dict.fromkeys(settings.simulate_list) if name in specs]
            sensors = listed or [
                spec.id for spec in config.devices if isinstance(spec.params, UltrasonicParams)
            ]
        sensor_rows, rays = [], []
        for name in sensors:
            found = specs.get(name)
            if found is None or not isinstance(found.params, UltrasonicParams):
                kinds = ", ".join(
                    s.id for s in config.devices if isinstance(s.params, UltrasonicParams)
                )
                raise BatchError(
                    f"batch sensors: {name!r} is not an ultrasonic sensor of this configuration "
                    f"(a batch reads ultrasonic sensors; this one has: {kinds or 'none'})"
                )
            p = found.params
            height = p.height
            if height is None and len(p.position) == 3:
                height = p.position[2]
            sensor_rows.append(
                (
                    p.position[0],
                    p.position[1],
                    p.rotation,
                    p.beamwidth,
                    p.min_range,
                    p.max_range,
                    p.error,
                    math.nan if height is None else height,
                )
            )
            rays.append(p.num_rays)
        channels: list[str] = []
        drive_channel = []
        for name, drive_row in zip(drive_ids, drive_rows, strict=True):
            drive_channel.append(len(channels) if drive_row[4] != 0.0 else -1)
            if drive_row[4] != 0.0:
                channels.append(name)
        sensor_channel = []
        for name, sensor_row in zip(sensors, sensor_rows, strict=True):
            sensor_channel.append(len(channels) if sensor_row[6] != 0.0 else -1)
            if sensor_row[6] != 0.0:
                channels.append(name)
        maze = Maze.from_settings(settings)
        outline = robot_outline(settings)
        free, free_loss, radius = _outline_samples(outline, maze.cell)
        rows, cols = maze.solid.shape
        field_step = max(maze.cell / FIELD_CELL, math.sqrt(rows * cols / FIELD_NODES) * maze.cell)
        field = (
            _wall_field(maze.hwall, maze.vwall, maze.solid, maze.cell, field_step)
            if len(free)
            else np.zeros((0, 0))
        )
        return cls(
            config=config,
            maze=maze,
            zones=Zones.from_settings(settings),
            dt=1.0 / settings.frame_rate,
            outline=outline,
            drive_ids=tuple(drive_ids),
            drives=np.array(drive_rows, dtype=np.float64).reshape(-1, 5),
            sensor_ids=tuple(sensors),
            sensors=np.array(sensor_rows, dtype=np.float64).reshape(-1, 8),
            sensor_rays=np.array(rays, dtype=np.int64),
            channels=tuple(channels),
            drive_channel=np.array(drive_channel, dtype=np.int64),
            sensor_channel=np.array(sensor_channel, dtype=np.int64),
            free=free,
            free_loss=free_loss,
            field=field,
            field_step=field_step,
            radius=radius,
        )

    @property
    def max_rays(self) -> int:
        return int(self.sensor_rays.max()) if len(self.sensor_rays) else 1


def _outline_samples(outline: FloatArray, cell: float) -> tuple[FloatArray, float, float]:
    """Points along the outline's edges at most ``FREE_SPACING`` apart, half the largest gap
    (a point of an edge is that close to a sample) and the outline's farthest point from the
    centre. None when the outline spans a cell or more: then a polygon could enclose a wall
    without its edges coming near one, and every step is tested."""
    radius = float(np.hypot(outline[:, 0], outline[:, 1]).max())
    span = np.hypot(*(outline[:, None, :] - outline[None, :, :]).transpose(2, 0, 1)).max()
    if span >= cell * 0.99:
        return np.zeros((0, 2)), 0.0, radius
    points, gap = list(outline), 0.0  # the corners first: the likeliest to be near a wall
    for a, b in zip(outline, np.roll(outline, -1, axis=0), strict=True):
        length = float(np.hypot(*(b - a)))
        parts = max(1, math.ceil(length / FREE_SPACING))
        gap = max(gap, length / parts)
        points.extend(a + (b - a) * (k / parts) for k in range(1, parts))
    return np.array(points, dtype=np.float64), gap / 2.0, radius


# --------------------------------------------------------------------------- the batch


class Batch:
    """N robots of one configuration, robot i seeded ``seeds[i]``, stepped in one compiled call.

    ``sensors`` names the ultrasonic sensors read every step (default: the configuration's
    ``simulate_list``, else every ultrasonic sensor), as a run reads its ``simulate_list``.
    Arrays (``poses``, ``readings``, ``collisions``...) are live views, one row per robot.
    """

    def __init__(
        self,
        config: SimConfig | str | Path | None,
        seeds: Sequence[int] | NDArray[np.integer],
        sensors: Sequence[str] | None = None,
        *,
        threads: int = 1,
    ) -> None:
        self.config = as_config(config)
        self._layout = layout = _Layout.of(self.config, sensors)
        if not 1 <= threads <= _MAX_THREADS:
            raise BatchError(
                f"threads must be 1 to {_MAX_THREADS} (this machine's "
                f"threads for Numba), not {threads}"
            )
        self.threads = threads
        """Numba threads a step runs on (1: the calling thread only, the default: a machine
        shared by a sweep's workers gains nothing from more)."""
        n = len(seeds)
        if not 1 <= n <= MAX_ROBOTS:
            raise BatchError(f"a batch holds 1 to {MAX_ROBOTS:,} robots (batch_robots), not {n:,}")
        drives, sensed, channels = (
            len(layout.drive_ids),
            len(layout.sensor_ids),
            len(layout.channels),
        )
        self.seeds = np.zeros(n, dtype=np.int64)
        self.poses = np.zeros((n, 3))
        """(N, 3): x, y (inches) and heading (degrees) of every robot."""
        self.readings = np.full((n, sensed), math.nan)
        """(N, S): each sensor's reading in the last step (NaN before the first)."""
        self.remaining = np.zeros((n, drives))
        self.collisions = np.zeros(n, dtype=np.int64)
        """Collisions so far (a run of blocked steps counts once), per robot."""
        self.blocked_steps = np.zeros(n, dtype=np.int64)
        self.steps = np.zeros(n, dtype=np.int64)
        """Simulation steps since each robot's reset."""
        self._was_blocked = np.zeros(n, dtype=np.bool_)
        self._bias = np.zeros((n, drives, 3))
        self._block_poly = np.zeros((n, 4, 2))
        self._block_seg = np.zeros((n, 4, 4))
        self._block_xy = np.zeros((n, 2))
        self._block_size = np.zeros(n)
        self._noise = np.zeros((n, channels, NOISE_BLOCK))
        self._cursor = np.full((n, channels), NOISE_BLOCK, dtype=np.int64)
        self._streams: list[list[np.random.Generator]] = [[] for _ in range(n)]
        self._none = np.full(n, -1, dtype=np.int64)
        self._zero = np.zeros(n)
        self._all = np.ones(n, dtype=np.bool_)
        self._replies = np.full(n, math.nan)
        self.reset(np.arange(n), seeds)

    @classmethod
    def from_config(
        cls, path: str | Path | None, seeds: Sequence[int], sensors: Sequence[str] | None = None
    ) -> Batch:
        """Load a configuration file (None: the built-in default) and build a batch."""
        return cls(load_config(path), seeds, sensors)

    def __len__(self) -> int:
        return len(self.poses)

    @property
    def drive_ids(self) -> tuple[str, ...]:
        """The drives, in the order :meth:`step`'s drive indices count them."""
        return self._layout.drive_ids

    @property
    def sensor_ids(self) -> tuple[str, ...]:
        """The sensors read every step, in the order of :attr:`readings`' columns."""
        return self._layout.sensor_ids

    @property
    def dt(self) -> float:
        """Seconds per simulation step (1 / frame_rate)."""
        return self._layout.dt

    @property
    def moving(self) -> BoolArray:
        """(N,): True where a robot's drive still has commanded motion left."""
        return np.asarray((self.remaining != 0.0).any(axis=1))

    @property
    def block_poses(self) -> FloatArray:
        """(N, 2): each robot's block centre (a random scenario places it per seed)."""
        return self._block_xy

    def drive_index(self, drive: str) -> int:
        """The index of drive ``drive`` (``"w0"``) for :meth:`step`."""
        try:
            return self._layout.drive_ids.index(drive)
        except ValueError:
            known = ", ".join(self._layout.drive_ids) or "none"
            raise BatchError(f"no drive {drive!r} on this robot (its drives: {known})") from None

    def reset(
        self,
        robots: Sequence[int] | NDArray[np.integer],
        seeds: Sequence[int] | NDArray[np.integer],
    ) -> None:
        """Put ``robots`` back to their start as new simulations seeded ``seeds`` start:
        the scenario, any drawn bias and every noise stream come from the seed."""
        layout = self._layout
        settings = self.config.settings
        robots = np.asarray(robots, dtype=np.int64)
        if len(robots) != len(seeds):
            raise BatchError(f"reset: {len(robots)} robots but {len(seeds)} seeds")
        linear, rotational = settings.bias_strength
        noisy = layout.channels
        for i, raw in zip(robots.tolist(), list(seeds), strict=True):
            seed = settings.run_seed(int(raw))

            def stream(source: str, seed: int = seed) -> np.random.Generator:
                return source_stream(seed, source)

            scenario = draw_scenario(settings, layout.maze, layout.zones, stream)
            block = Block(*scenario.block, settings.block_rotation, settings.block_size)
            self.seeds[i] = seed
            self.poses[i] = scenario.start
            self._block_poly[i] = block.polygon
            self._block_seg[i] = block.segments
            self._block_xy[i] = (block.x, block.y)
            self._block_size[i] = block.size
            for d, name in enumerate(layout.drive_ids):
                params = self._drive_params(name)
                bias = (params.bias.x, params.bias.y, params.bias.rotation)
                if settings.rand_bias:
                    rng = stream(f"bias:{name}")
                    x, y = rng.normal(0.0, linear, 2) if linear else (0.0, 0.0)
                    rotational_drive = layout.drives[d, 0] == 0.0 and layout.drives[d, 1] == 0.0
                    spread = linear if rotational_drive else rotational
                    rotation = float(rng.normal(0.0, spread)) if spread else 0.0
                    bias = (float(x), float(y), rotation)
                self._bias[i, d] = bias
            self._streams[i] = [stream(f"device:{name}") for name in noisy]
        self.remaining[robots] = 0.0
        self.readings[robots] = math.nan
        self.collisions[robots] = 0
        self.blocked_steps[robots] = 0
        self.steps[robots] = 0
        self._was_blocked[robots] = False
        self._cursor[robots] = NOISE_BLOCK

    def _drive_params(self, name: str) -> DriveParams:
        for spec in self.config.devices:
            if spec.id == name and isinstance(spec.params, DriveParams):
                return spec.params
        raise BatchError(f"no drive {name!r}")  # pragma: no cover (the layout found it)

    def _refill(self, need: int) -> None:
        """Make sure every robot's every channel has ``need`` noise values left, drawing the
        next block from its stream (the values a scalar draw would give, in order)."""
        cursor = self._cursor
        if cursor.size == 0:
            return
        low = np.argwhere(cursor > NOISE_BLOCK - need)
        noise = self._noise
        for i, c in low.tolist():
            k = int(cursor[i, c])
            left = NOISE_BLOCK - k
            noise[i, c, :left] = noise[i, c, k:]
            noise[i, c, left:] = self._streams[i][c].normal(0.0, 2.0, k)
            cursor[i, c] = 0

    def step(
        self,
        drive: NDArray[np.integer] | None = None,
        amount: NDArray[np.floating] | None = None,
        steps: int = 1,
        active: BoolArray | None = None,
    ) -> FloatArray:
        """Give robot i the command ``drive[i]``-``amount[i]`` (a drive index, -1 for none),
        then advance every robot ``steps`` simulation steps, reading its sensors each step.
        ``active`` (N,): only these robots (the others stand still, their noise untouched).

        Returns (N,) replies as a drive answers: +inf accepted, NaN refused (a drive still
        moving) or no command. ``steps`` > 1 is as many calls of ``steps=1`` without commands.
        """
        n = len(self.poses)
        if drive is None:
            drive, amount = self._none, self._zero
        drives: IntArray = np.ascontiguousarray(drive, dtype=np.int64)
        amounts: FloatArray = np.ascontiguousarray(amount, dtype=np.float64)
        if drives.shape != (n,) or amounts.shape != (n,):
            raise BatchError(f"step: drive and amount must each have {n} values, one per robot")
        if ((drives < -1) | (drives >= len(self._layout.drive_ids))).any():
            raise BatchError(f"step: a drive index is -1 (none) or 0 to {len(self.drive_ids) - 1}")
        if not np.isfinite(amounts[drives >= 0]).all():
            raise BatchError("step: a commanded amount must be a finite number")
        if steps < 1:
            raise BatchError(f"step: steps must be 1 or more, not {steps}")
        if active is None:
            active = self._all
        active = np.ascontiguousarray(active, dtype=np.bool_)
        if active.shape != (n,):
            raise BatchError(f"step: active must have {n} values, one per robot")
        layout = self._layout
        replies = self._replies
        replies[:] = math.nan
        kernel = _step_parallel if self.threads > 1 else _step
        chunks = self.threads * 4 if self.threads > 1 else 1
        if self.threads > 1:
            numba.set_num_threads(self.threads)
        done = 0
        while done < steps:
            chunk = min(steps - done, NOISE_BLOCK // 2)
            self._refill(chunk + 1)
            maze = layout.maze
            kernel(
                chunk,
                layout.dt,
                self.poses,
                self.remaining,
                self._was_blocked,
                self.collisions,
                self.blocked_steps,
                drives if done == 0 else self._none,
                amounts,
                replies,
                layout.drives,
                layout.drive_channel,
                self._bias,
                layout.outline,
                layout.free,
                layout.free_loss,
                layout.field,
                layout.field_step,
                layout.radius,
                maze.hwall,
                maze.vwall,
                maze.solid,
                maze.cell,
                maze.segments,
                self._block_poly,
                self._block_seg,
                self._block_xy,
                self._block_size,
                layout.sensors,
                layout.sensor_rays,
                layout.sensor_channel,
                self._noise,
                self._cursor,
                self.readings,
                active,
                chunks,
            )
            done += chunk
        self.steps[active] += steps
        return replies.copy()

    def command(self, commands: Sequence[str | None], steps: int = 1) -> FloatArray:
        """:meth:`step` with a command per robot as text (``"w0-6"``, ``"r0--90"``, None)."""
        drive = np.full(len(self.poses), -1, dtype=np.int64)
        amount = np.zeros(len(self.poses))
        for i, text in enumerate(commands):
            if text is None:
                continue
            name, _, value = text.partition("-")
            try:
                amount[i] = float(value)
            except ValueError:
                raise BatchError(f"command {text!r}: the form is drive-amount, e.g. w0-6") from None
            drive[i] = self.drive_index(name)
        return self.step(drive, amount, steps)


# --------------------------------------------------------------------------- the model


class Model:
    """The motion and sensor model of a configuration for N hypothetical poses at once (a
    particle filter's predict and weight steps), with the simulator's own geometry.

    The block is where the configuration puts it (``block=False``: walls only).
    """

    def __init__(
        self,
        config: SimConfig | str | Path | None,
        sensors: Sequence[str] | None = None,
        *,
        block: bool = True,
    ) -> None:
        self.config = as_config(config)
        self._layout = layout = _Layout.of(self.config, sensors)
        settings = self.config.settings
        shown = Block.from_settings(settings)
        self._block_poly = shown.polygon[None].copy()
        self._block_seg = shown.segments[None].copy()
        self._block_xy = np.array([[shown.x, shown.y]])
        self._block_size = np.array([shown.size])
        if not block:  # a block far outside the maze: never seen, never touched
            far = 1e9
            self._block_poly += far
            self._block_seg += far
            self._block_xy += far
        self._rays = np.empty(layout.max_rays)

    @property
    def sensor_ids(self) -> tuple[str, ...]:
        """The sensors :meth:`read` and :meth:`expected` give, in column order."""
        return self._layout.sensor_ids

    @property
    def cell(self) -> float:
        """Inches: the side of the maze's square cells (a move of one cell, a particle's cell)."""
        return self._layout.maze.cell

    @property
    def open_cells(self) -> IntArray:
        """(K, 2): row and column of every open cell of the maze, where a robot can be (cell
        (r, c) spans x from c to c + 1 cells, y from r to r + 1)."""
        return np.argwhere(~self._layout.maze.solid).astype(np.int64)

    def move(
        self,
        poses: FloatArray,
        drive: str,
        amount: float,
        rng: np.random.Generator | None = None,
        max_steps: int = 3600,
    ) -> FloatArray:
        """Where each of N poses ((N, 3): x, y, heading) ends up after the command
        ``drive``-``amount``, under the drive's error (drawn from ``rng``; None: no error) and
        its configured bias, stopped by walls and the block as the robot is: (N, 3)."""
        layout = self._layout
        poses = np.array(poses, dtype=np.float64).reshape(-1, 3)
        n = len(poses)
        try:
            d = layout.drive_ids.index(drive)
        except ValueError:
            known = ", ".join(layout.drive_ids) or "none"
            raise BatchError(f"no drive {drive!r} on this robot (its drives: {known})") from None
        if not math.isfinite(amount):
            raise BatchError(f"move: {amount!r} is not a distance")
        drives = layout.drives
        remaining = np.zeros((n, len(drives)))
        remaining[:, d] = amount
        if rng is not None and drives[d, 4] != 0.0 and amount != 0.0:
            remaining[:, d] += rng.normal(0.0, 2.0, n) * drives[d, 4] * amount
        bias = np.zeros((n, len(drives), 3))
        params = [
            spec.params for spec in self.config.devices if isinstance(spec.params, DriveParams)
        ]
        for e, p in enumerate(params):
            bias[:, e] = (p.bias.x, p.bias.y, p.bias.rotation)
        speed = drives[d, 3] * layout.dt
        steps = min(max_steps, math.ceil(abs(amount) * 1.5 / speed) + 2 if speed else 1)
        no_sensors = np.zeros((0, 8))
        maze = layout.maze
        _step(
            steps,
            layout.dt,
            poses,
            remaining,
            np.zeros(n, dtype=np.bool_),
            np.zeros(n, dtype=np.int64),
            np.zeros(n, dtype=np.int64),
            np.full(n, -1, dtype=np.int64),
            np.zeros(n),
            np.zeros(n),
            drives,
            layout.drive_channel,
            bias,
            layout.outline,
            layout.free,
            layout.free_loss,
            layout.field,
            layout.field_step,
            layout.radius,
            maze.hwall,
            maze.vwall,
            maze.solid,
            maze.cell,
            maze.segments,
            np.broadcast_to(self._block_poly, (n, 4, 2)),
            np.broadcast_to(self._block_seg, (n, 4, 4)),
            np.broadcast_to(self._block_xy, (n, 2)),
            np.broadcast_to(self._block_size, (n,)),
            no_sensors,
            np.zeros(0, dtype=np.int64),
            np.zeros(0, dtype=np.int64),
            np.zeros((n, 0, 1)),
            np.zeros((n, 0), dtype=np.int64),
            np.zeros((n, 0)),
            np.ones(n, dtype=np.bool_),
            1,
        )
        return poses

    def read(self, poses: FloatArray, rng: np.random.Generator | None = None) -> FloatArray:
        """Each sensor's reading at each of N poses, (N, S), with each sensor's error drawn
        from ``rng`` (None: noise-free, as :meth:`expected`)."""
        layout = self._layout
        poses = np.ascontiguousarray(poses, dtype=np.float64).reshape(-1, 3)
        n = len(poses)
        s = len(layout.sensor_ids)
        if rng is None:
            channel = np.full(s, -1, dtype=np.int64)
            noise = np.zeros((n, 0, 1))
        else:
            channel = np.arange(s, dtype=np.int64)
            noise = rng.normal(0.0, 2.0, (n, s, 1))
        out = np.empty((n, s))
        maze = layout.maze
        _sense(
            poses,
            maze.hwall,
            maze.vwall,
            maze.cell,
            maze.segments,
            np.broadcast_to(self._block_seg, (n, 4, 4)),
            np.broadcast_to(self._block_xy, (n, 2)),
            np.broadcast_to(self._block_size, (n,)),
            layout.sensors,
            layout.sensor_rays,
            channel,
            self._rays,
            noise,
            out,
        )
        return out

    def expected(self, poses: FloatArray) -> FloatArray:
        """Noise-free readings at each of N poses, (N, S)."""
        return self.read(poses, None)
