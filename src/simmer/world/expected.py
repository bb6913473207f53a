"""Noise-free readings at many poses at once, with the simulator's own geometry.

:func:`expected` answers for ultrasonic, infrared, compass and time-of-flight sensors and
LiDARs exactly what each reads with its noise off (the same ray-casting and floor kernels,
:mod:`simmer.geometry`). Gyroscopes, IMUs and encoders (they sense motion: no function of the
pose), motors, drives and device kinds of your own are refused by name. The ultrasonic fans
are cast in parallel over the poses (Numba ``prange``), so a lookup table of millions of poses
takes seconds (:func:`table`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numba
import numpy as np

from simmer.devices.lidar import Lidar, beam_vectors
from simmer.devices.sensors import _DISK, Compass, Infrared, Ultrasonic
from simmer.devices.tof import MM_PER_INCH, TimeOfFlight
from simmer.geometry import (
    BoolArray,
    FloatArray,
    cast_fan,
    lidar_beam,
    white_fraction,
    wrap_degrees,
)

if TYPE_CHECKING:
    from simmer.world.simulation import Simulation

SUPPORTED = ("ultrasonic", "infrared", "compass", "tof", "lidar")
"""Sensor kinds :func:`expected` answers for (a LiDAR only when named: a column per beam)."""
POSE_SENSORS = (Ultrasonic, Infrared, Compass, TimeOfFlight)
"""The sensors whose one reading is a function of the pose: the default columns."""


@numba.njit(cache=True, nogil=True, parallel=True)
def _fans(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block: FloatArray,
    block_xy: FloatArray,
    poses: FloatArray,
    mount: FloatArray,
    rays: int,
    out: FloatArray,
) -> None:
    """Fill ``out[i]`` with the noise-free reading of one ultrasonic sensor at ``poses[i]``.

    ``mount``: x, y, rotation, beamwidth, min_range, max_range, height above the block's top
    (``block_xy[2]`` > 0: the block is there to be seen). The arithmetic is
    :meth:`~simmer.devices.base.Device.world_pose`'s, then :func:`~simmer.geometry.cast_fan`
    itself, so the readings are the sensor's own to the last bit.
    """
    px, py, rotation, beamwidth, low, high, above = (
        mount[0],
        mount[1],
        mount[2],
        mount[3],
        mount[4],
        mount[5],
        mount[6],
    )
    with_block = block_xy[2] > 0.0
    for i in numba.prange(poses.shape[0]):
        scratch = np.empty(rays)  # each thread its own rays
        rx, ry, rh = poses[i, 0], poses[i, 1], poses[i, 2]
        rad = math.radians(rh)
        c, s = math.cos(rad), math.sin(rad)
        ox = rx + px * c - py * s
        oy = ry + px * s + py * c
        heading = rh + rotation
        sees = False
        if with_block:
            d = math.hypot(block_xy[0] - ox, block_xy[1] - oy)
            sees = math.degrees(math.atan2(above, d)) <= beamwidth / 2.0
        best = cast_fan(
            hwall, vwall, cell, fallback, block, sees, ox, oy, heading, beamwidth, high, scratch
        )
        out[i] = high if best == math.inf else min(max(best, low), high)


@numba.njit(cache=True, nogil=True, parallel=True)
def _floors(
    floor_white: BoolArray,
    tile: float,
    disk: FloatArray,
    poses: FloatArray,
    mount: FloatArray,
    out: FloatArray,
) -> None:
    """Fill ``out[i]`` with an infrared sensor's noise-free reading at ``poses[i]`` (1 white,
    0 black). ``mount``: x, y, radius, threshold; the arithmetic is the sensor's own."""
    px, py, radius, threshold = mount[0], mount[1], mount[2], mount[3]
    for i in numba.prange(poses.shape[0]):
        rad = math.radians(poses[i, 2])
        c, s = math.cos(rad), math.sin(rad)
        x = poses[i, 0] + px * c - py * s
        y = poses[i, 1] + px * s + py * c
        fraction = white_fraction(floor_white, tile, x, y, radius, disk)
        out[i] = 1.0 if fraction >= threshold else 0.0


@numba.njit(cache=True, nogil=True, parallel=True)
def _scans(
    hwall: BoolArray,
    vwall: BoolArray,
    cell: float,
    fallback: FloatArray,
    block: FloatArray,
    see_block: bool,
    poses: FloatArray,
    mount: FloatArray,
    vectors: FloatArray,
    low: float,
    high: float,
    out: FloatArray,
) -> None:
    """Fill ``out[i, k]`` with a LiDAR's noise-free beam k at robot pose ``poses[i]`` (0: no
    return). ``mount``: x, y; ``vectors``: each beam's unit vector at heading 0 (the device's
    ``vectors``); the arithmetic is :func:`~simmer.geometry.scan_revolution`'s, beam by beam,
    so the readings are the device's own to the last bit."""
    px, py = mount[0], mount[1]
    for i in numba.prange(poses.shape[0]):
        rad = math.radians(poses[i, 2])
        c = math.cos(rad)
        s = math.sin(rad)
        ox = poses[i, 0] + px * c - py * s
        oy = poses[i, 1] + px * s + py * c
        for k in range(vectors.shape[1]):
            ex, ey = vectors[0, k], vectors[1, k]
            dx = c * ex - s * ey
            dy = s * ex + c * ey
            d = lidar_beam(hwall, vwall, cell, fallback, block, see_block, ox, oy, dx, dy, high)
            out[i, k] = 0.0 if (d == math.inf or d < low or d > high) else d


def _as_poses(poses: Any) -> FloatArray:
    array = np.ascontiguousarray(poses, dtype=np.float64)
    if array.ndim == 1 and array.shape[0] == 3:
        array = array.reshape(1, 3)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(
            f"poses must be (x, y, heading) rows, an array of shape (N, 3); got {array.shape}"
        )
    return array


def expected(
    sim: Simulation,
    poses: Any,
    sensors: Sequence[str] | None = None,
    *,
    block: bool = True,
) -> FloatArray:
    """Noise-free readings of ``sensors`` (default: every supported sensor) at ``poses``.

    ``poses``: (N, 3) x, y, heading (inches, degrees from +y) of the robot. Returns (N, S), one
    column per sensor in the order asked. ``block``: the block, where it is now, is seen by the
    ultrasonic sensors and LiDARs as in the simulation (False: the walls alone, as for a table
    made before anyone knows where the block is). A pose inside a wall is not refused: its rays
    start there. A LiDAR, when named (the default leaves it out), gives one column per beam,
    beam 0 first: its scan with its noise off and the robot standing still (0: no return).
    """
    array = _as_poses(poses)
    devices = sim.robot.sensors
    if sensors is None:
        sensors = [i for i, d in devices.items() if isinstance(d, POSE_SENSORS)]
    found = []
    for sensor_id in sensors:
        device = devices.get(sensor_id)
        if device is None:
            known = ", ".join(devices) or "none"
            raise ValueError(f"no sensor {sensor_id!r} on the robot; the sensors are: {known}")
        found.append(device)
    widths = [d.settings.beams if isinstance(d, Lidar) else 1 for d in found]
    out = np.empty((array.shape[0], sum(widths)), dtype=np.float64)
    column = 0
    for device, width in zip(found, widths, strict=True):
        if isinstance(device, Lidar):
            out[:, column : column + width] = _lidar(sim, device, array, block)
        else:
            out[:, column] = _column(sim, device, array, block)
        column += width
    return out


def _lidar(sim: Simulation, device: Lidar, poses: FloatArray, block: bool) -> FloatArray:
    """A LiDAR's noise-free scans at ``poses``: (N, beams)."""
    s = device.settings
    maze, cube = sim.maze, sim.block
    out = np.empty((poses.shape[0], s.beams), dtype=np.float64)
    _scans(
        maze.hwall,
        maze.vwall,
        maze.cell,
        maze.segments,
        cube.segments,
        block and device.sees_block(sim),
        poses,
        device.mount,
        device.vectors,
        s.min_range,
        s.max_range,
        out,
    )
    return out


def _column(sim: Simulation, device: Any, poses: FloatArray, block: bool) -> FloatArray:
    column = np.empty(poses.shape[0], dtype=np.float64)
    if isinstance(device, Ultrasonic):
        s = device.settings
        maze, cube = sim.maze, sim.block
        above = device.height(sim) - cube.size
        mount = np.array(
            [*device.position, device.rotation, s.beamwidth, s.min_range, s.max_range, above]
        )
        where = np.array([cube.x, cube.y, 1.0 if block else 0.0])
        _fans(
            maze.hwall,
            maze.vwall,
            maze.cell,
            maze.segments,
            cube.segments,
            where,
            poses,
            mount,
            s.num_rays,
            column,
        )
    elif isinstance(device, TimeOfFlight):
        _tof_column(sim, device, poses, block, column)
    elif isinstance(device, Infrared):
        maze = sim.maze
        mount = np.array([*device.position, device.radius, device.settings.threshold])
        _floors(maze.floor_white, maze.tile, _DISK, poses, mount, column)
    elif isinstance(device, Compass):
        offset = device.rotation + device.settings.bias
        column[:] = [wrap_degrees(float(h) + offset) for h in poses[:, 2]]
    else:
        kind = type(device).kind or "its own kind"
        raise ValueError(
            f"sensor {device.id!r} ({kind}): expected readings are for {', '.join(SUPPORTED)} "
            "sensors (a gyroscope integrates turns, so its reading is no function of the pose)"
        )
    return column


def _tof_column(
    sim: Simulation, device: TimeOfFlight, poses: FloatArray, block: bool, column: FloatArray
) -> None:
    """A time-of-flight sensor's noise-free readings: the ultrasonic fan kernel over its cone
    (no lower clamp), then the driver's out-of-range value and the sensor's units."""
    maze, cube = sim.maze, sim.block
    above = device.height(sim) - cube.size
    mount = np.array([*device.position, device.rotation, device.fov, 0.0, device.max_range, above])
    where = np.array([cube.x, cube.y, 1.0 if block else 0.0])
    _fans(
        maze.hwall,
        maze.vwall,
        maze.cell,
        maze.segments,
        cube.segments,
        where,
        poses,
        mount,
        device.settings.num_rays,
        column,
    )
    units = device.settings.units
    reach = column >= device.max_range
    if units == "mm":
        column[:] = np.round(column * MM_PER_INCH)  # as in_units rounds
    column[reach] = device.out_of_range


# ----------------------------------------------------------------------------- tables


def parse_headings(text: str) -> FloatArray:
    """``START:STOP:STEP`` in degrees (``0:360:1``: 360 headings, STOP left out) as an array."""
    parts = text.split(":")
    try:
        start, stop, step = (float(p) for p in parts)
    except ValueError:
        raise ValueError(
            f"headings {text!r}: write START:STOP:STEP in degrees, e.g. 0:360:1"
        ) from None
    if not all(-MAX_HEADING_DEGREES <= value <= MAX_HEADING_DEGREES for value in (start, stop)):
        raise ValueError(
            f"headings {text!r}: START and STOP are degrees from {-MAX_HEADING_DEGREES:,.0f} to "
            f"{MAX_HEADING_DEGREES:,.0f} (MAX_HEADING_DEGREES), e.g. 0:360:1"
        )
    if not math.isfinite(step) or step <= 0 or stop <= start:
        raise ValueError(f"headings {text!r}: STEP must be positive and STOP above START")
    if (stop - start) / step > MAX_HEADINGS:  # before ceil(): a tiny STEP makes infinity
        raise ValueError(
            f"headings {text!r}: more than {MAX_HEADINGS} headings (MAX_HEADINGS); use a "
            "larger STEP"
        )
    count = max(1, math.ceil((stop - start) / step - 1e-9))  # START at least
    return start + step * np.arange(count, dtype=np.float64)


MAX_HEADINGS = 3600
"""Most headings in a table (a tenth of a degree)."""
MAX_HEADING_DEGREES = 3600.0
"""Largest START or STOP of a table's headings, either sign (ten turns): beyond a turn a
heading only repeats one, and ``-1e308:1e308`` overflowed the count."""
MAX_TABLE_VALUES = 200_000_000
"""Most readings in a table (1.6 GB as float64 while it is made); ``--step`` larger makes
fewer."""


def grid(sim: Simulation, step: float) -> tuple[FloatArray, FloatArray]:
    """The x and y of a table's positions: every ``step`` inches, half a step from the edges."""
    if not (math.isfinite(step) and step > 0):
        raise ValueError(f"step must be a positive number of inches, not {step!r}")
    maze = sim.maze
    if (maze.width / step) * (maze.height / step) > MAX_TABLE_VALUES:  # before arange()
        raise ValueError(
            f"--step {step!r} makes more positions than the limit of {MAX_TABLE_VALUES:,} "
            "readings (MAX_TABLE_VALUES); use a larger --step"
        )
    xs = np.arange(step / 2.0, maze.width, step)
    ys = np.arange(step / 2.0, maze.height, step)
    if not (len(xs) and len(ys)):
        raise ValueError(
            f"--step {step!r} leaves no position inside the maze ({maze.width:g} x "
            f"{maze.height:g} in); use a smaller --step"
        )
    return xs, ys


def table(
    sim: Simulation,
    step: float,
    headings: FloatArray,
    sensors: Sequence[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[FloatArray, FloatArray, list[str], FloatArray]:
    """Readings on a grid: (xs, ys, sensor ids, readings[y, x, heading, sensor]).

    Positions in solid cells read NaN. The block is left out (a table is made before anyone
    knows where the block is). ``progress(done, total)`` is called after each row of y.
    """
    xs, ys = grid(sim, step)
    if sensors is None:
        sensors = [i for i, d in sim.robot.sensors.items() if isinstance(d, POSE_SENSORS)]
    sensors = list(sensors)
    total = len(xs) * len(ys) * len(headings) * max(1, len(sensors))
    if total > MAX_TABLE_VALUES:
        raise ValueError(
            f"{total:,} readings is over the limit of {MAX_TABLE_VALUES:,}; use a larger --step, "
            "fewer headings or fewer sensors"
        )
    out = np.full((len(ys), len(xs), len(headings), len(sensors)), np.nan)
    gx, gh = np.meshgrid(xs, headings, indexing="ij")
    maze = sim.maze
    for row, y in enumerate(ys):
        cols = np.minimum((xs // maze.cell).astype(int), maze.cols - 1)
        cell_row = min(int(y // maze.cell), maze.rows - 1)
        open_x = ~maze.solid[cell_row, cols]
        if open_x.any():
            poses = np.column_stack(
                (gx[open_x].ravel(), np.full(gh[open_x].size, y), gh[open_x].ravel())
            )
            values = expected(sim, poses, sensors, block=False)
            out[row, open_x] = values.reshape(int(open_x.sum()), len(headings), len(sensors))
        if progress is not None:
            progress(row + 1, len(ys))
    return xs, ys, sensors, out


def lidar_table(
    sim: Simulation, step: float, sensor: str, progress: Callable[[int, int], None] | None = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """A LiDAR's scans on a grid, from the walls alone: (xs, ys, readings[y, x, beam]).

    ``readings[y, x, k]`` is beam k of the noise-free scan of LiDAR ``sensor`` with its centre
    at (x, y) and its front facing heading 0 (beam k along heading ``360 k / beams``; 0: no
    return; NaN in solid cells). Positions are the LiDAR's own, not the robot's centre. A full
    circle turned is the same circle, so this one heading is the whole table: the LiDAR at
    (x, y) facing heading ``h`` (the robot's heading plus its ``rotation``) reads
    ``np.roll(readings[y, x], -round(h * beams / 360))``, exactly when ``h`` is a whole
    number of beams.
    """
    device = sim.robot.sensors.get(sensor)
    if not isinstance(device, Lidar):
        lidars = [i for i, d in sim.robot.sensors.items() if isinstance(d, Lidar)]
        raise ValueError(
            f"{sensor!r} is not a LiDAR on the robot; its LiDARs are: {', '.join(lidars) or 'none'}"
        )
    xs, ys = grid(sim, step)
    s = device.settings
    beams = s.beams
    total = len(xs) * len(ys) * beams
    if total > MAX_TABLE_VALUES:
        raise ValueError(
            f"{total:,} readings is over the limit of {MAX_TABLE_VALUES:,} (MAX_TABLE_VALUES); "
            "use a larger --step"
        )
    out = np.full((len(ys), len(xs), beams), np.nan)
    maze = sim.maze
    cols = np.minimum((xs // maze.cell).astype(int), maze.cols - 1)
    for row, y in enumerate(ys):
        open_x = ~maze.solid[min(int(y // maze.cell), maze.rows - 1), cols]
        if open_x.any():
            poses = np.column_stack(
                (xs[open_x], np.full(int(open_x.sum()), y), np.zeros(int(open_x.sum())))
            )
            scans = np.empty((poses.shape[0], beams))
            _scans(
                maze.hwall,
                maze.vwall,
                maze.cell,
                maze.segments,
                sim.block.segments,
                False,
                poses,
                np.zeros(3),
                beam_vectors(device.directions, 0.0),
                s.min_range,
                s.max_range,
                scans,
            )
            out[row, open_x] = scans
        if progress is not None:
            progress(row + 1, len(ys))
    return xs, ys, out
