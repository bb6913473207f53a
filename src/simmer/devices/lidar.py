"""The ``lidar`` kind: a spinning 2D laser scanner modelled on the Slamtec RPLidar A1M8.

Datasheet figures used (RPLidar A1M8, Slamtec LD108): a 360 degree scan, 5.5 revolutions a
second by default (2 to 10 Hz as the motor is driven), about 2,000 samples a second, so about
one degree between samples at 5.5 Hz; range 0.15 to 12 m (5.9 to 472 in); distance
resolution below 1% of the range. The defaults below follow them.

A scan takes one revolution of simulated time: beam k of a revolution that starts at ``t0``
is measured at ``t0 + k / (beams · scan_rate)``, from where the robot is then (the poses of
the steps around it, interpolated), so a turning robot's scan is smeared as the real one's
is (``motion_skew``; off: the whole scan from the pose at its end). A read answers from the
latest complete scan; before the first revolution ends that is the scan the spinning LiDAR
made at the start pose before the run began.

Noise, each from the device's own seeded stream in a fixed order (the normals NOISE_SCANS
revolutions at a time, made from the stream's raw bits by the ziggurat method:
:func:`fill_normals`; the dropout as the gaps between dropped beams):
``range_error + range_error_proportional · d`` inches standard deviation on a distance ``d``
(Stage's ranger model), ``angular_jitter`` degrees standard deviation on each beam's true
direction (the angle reported stays the nominal one), and ``dropout``, the chance a beam
returns nothing. A beam with no return (nothing within ``max_range``, closer than
``min_range``, or dropped) reads 0, as the RPLidar reports an invalid measurement (distance
0, quality 0).

Reads (docs/protocol.md): ``l0-A`` (0 <= A < 360) the distance in inches of the beam nearest
A degrees clockwise from the LiDAR's front; ``l0--1`` the beams per revolution; ``l0--2``
the number of the scan answering (it grows by one a revolution), so one message reads a
whole scan consistently: ``simmer.client.Client.scan``.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numba
import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from simmer.devices.base import Circle, Color, Device, DeviceParams, Shape, Whole, World
from simmer.devices.sensors import MeasuredParams
from simmer.errors import CommandError
from simmer.geometry import FloatArray, Vec2, rectangle, scan_revolution

MAX_BEAMS = 999
"""Most beams per revolution: a whole scan is read in one message of a command per beam plus
the scan number, within the protocol's 1,000 commands (``MAX_COMMANDS``)."""
NOISE_SCANS = 16
"""Revolutions whose noise a LiDAR draws at once (each a NumPy call for all of them)."""
ZIGGURAT_R = 3.442619855899
"""Where the 128-layer ziggurat's base strip ends and its tail begins (Marsaglia & Tsang,
"The ziggurat method for generating random variables", J. Stat. Softw. 5(8), 2000)."""
ZIGGURAT_V = 9.91256303526217e-3
"""The area of each of its layers (under exp(-x^2 / 2), the base strip's tail included)."""


def _ziggurat_tables() -> tuple[NDArray[np.int64], FloatArray, FloatArray]:
    """The ziggurat's tables: for layer i (0 the base, 127 the top), the integer below which
    a 24-bit draw lies wholly under the curve, the layer's width over 2^24, and exp(-x^2/2)
    at each layer's right edge (129: the top's is 1)."""
    r, v = ZIGGURAT_R, ZIGGURAT_V
    edges = [v / math.exp(-0.5 * r * r), r]  # the base's virtual width (v over its height), r
    for _ in range(126):
        x = edges[-1]
        edges.append(math.sqrt(-2.0 * math.log(math.exp(-0.5 * x * x) + v / x)))
    edges.append(0.0)
    below = np.array([int(2.0**24 * edges[i + 1] / edges[i]) for i in range(128)], np.int64)
    width = np.array([edges[i] / 2.0**24 for i in range(128)])
    height = np.array([math.exp(-0.5 * x * x) for x in edges])
    return below, width, height


_ZIG_BELOW, _ZIG_WIDTH, _ZIG_HEIGHT = _ziggurat_tables()


@numba.njit(cache=True, nogil=True)
def fill_normals(bits: NDArray[np.uint64], out: FloatArray, done: int) -> int:
    """Fill ``out[done:]`` with standard normals made from ``bits`` (uniform 64-bit draws,
    each used as two 32-bit words, low half first) by the ziggurat method (Marsaglia & Tsang
    2000, its 128 layers and 32-bit draws): exact to a step of 2^-24 of a layer's width
    (2e-7 sd), and about a fifth of NumPy's ``standard_normal``'s time here (half the bits,
    and its random sign is a branch the processor mispredicts half the time; here a
    multiply). A word is 7 bits of layer, one of sign, 24 of position; the rare word outside
    the layer's sure part takes one more for the wedge test, or two a try in the tail
    (Marsaglia's). Returns how many of ``out`` are filled: all, unless ``bits`` ran out."""
    words = 2 * bits.shape[0]
    size = out.shape[0]
    w = 0
    unit = 1.0 / 2.0**32
    mask = np.uint64(0xFFFFFFFF)
    while done < size and w < words:
        if w & 1 == 0 and done + 1 < size:  # both words of a draw, the common case at once
            pair = bits[w >> 1]
            low, high = pair & mask, pair >> np.uint64(32)
            la, lb = np.int64(low & np.uint64(0x7F)), np.int64(high & np.uint64(0x7F))
            ja, jb = np.int64(low >> np.uint64(8)), np.int64(high >> np.uint64(8))
            if ja < _ZIG_BELOW[la] and jb < _ZIG_BELOW[lb]:
                out[done] = (1.0 - 2.0 * np.float64((low >> np.uint64(7)) & np.uint64(1))) * (
                    ja * _ZIG_WIDTH[la]
                )
                out[done + 1] = (1.0 - 2.0 * np.float64((high >> np.uint64(7)) & np.uint64(1))) * (
                    jb * _ZIG_WIDTH[lb]
                )
                done += 2
                w += 2
                continue
        b = (bits[w >> 1] >> np.uint64(32 * (w & 1))) & mask  # one word, as it comes
        w += 1
        layer = np.int64(b & np.uint64(0x7F))
        sign = 1.0 - 2.0 * np.float64((b >> np.uint64(7)) & np.uint64(1))
        j = np.int64(b >> np.uint64(8))  # 24 bits
        x = j * _ZIG_WIDTH[layer]
        if j < _ZIG_BELOW[layer]:
            out[done] = sign * x
            done += 1
        elif layer == 0:  # the tail beyond r: uniforms in (0, 1), a word each
            while w + 2 <= words:
                u1 = (np.float64((bits[w >> 1] >> np.uint64(32 * (w & 1))) & mask) + 0.5) * unit
                w += 1
                u2 = (np.float64((bits[w >> 1] >> np.uint64(32 * (w & 1))) & mask) + 0.5) * unit
                w += 1
                tx = -math.log(u1) / ZIGGURAT_R
                if -2.0 * math.log(u2) > tx * tx:
                    out[done] = sign * (ZIGGURAT_R + tx)
                    done += 1
                    break
        elif w < words:  # the wedge: a height within the layer, under the curve or not
            u = (np.float64((bits[w >> 1] >> np.uint64(32 * (w & 1))) & mask) + 0.5) * unit
            w += 1
            low = _ZIG_HEIGHT[layer]
            if low + u * (_ZIG_HEIGHT[layer + 1] - low) < math.exp(-0.5 * x * x):
                out[done] = sign * x
                done += 1
    return done


def standard_normals(rng: np.random.Generator, out: FloatArray) -> None:
    """Fill ``out`` with standard normals from ``rng``'s bit stream (:func:`fill_normals`):
    the draws of a seed are always the same, though not NumPy's ``standard_normal``'s."""
    done = 0
    while done < len(out):
        wanted = len(out) - done
        draws = (wanted + wanted // 16) // 2 + 8  # two words a draw, and a few rejected
        done = fill_normals(rng.bit_generator.random_raw(draws), out, done)


BEAMS_READ = -1.0
"""``l0--1``: the beams per revolution."""
SCAN_NUMBER_READ = -2.0
"""``l0--2``: the number of the scan that answers."""


def beam_vectors(directions: FloatArray, rotation: float) -> FloatArray:
    """Unit vectors (2, N: x row, y row) of beams at ``directions`` degrees clockwise from a
    front turned ``rotation`` degrees from the robot's, at robot heading 0."""
    angle = np.radians(rotation + directions)
    return np.vstack((-np.sin(angle), np.cos(angle)))


class LidarParams(MeasuredParams):
    """A 2D scanning LiDAR's settings (defaults: the RPLidar A1M8's datasheet)."""

    type: str = "lidar"
    height: float | None = Field(
        None,
        gt=0,
        description="Height of the scan plane, inches; defaults to the third position value, "
        "else the robot's height (on top). Below the block's top it sees the block.",
    )
    beams: Whole = Field(360, ge=1, description="Beams per revolution (999 at most, MAX_BEAMS).")
    scan_rate: float = Field(5.5, gt=0, le=100, description="Revolutions per second.")
    min_range: float = Field(5.9, ge=0, description="Shortest distance it measures, inches.")
    max_range: float = Field(472.0, gt=0, description="Longest distance it measures, inches.")
    range_error: float = Field(
        0.02, ge=0, description="Constant part of the distance noise's sd, inches."
    )
    range_error_proportional: float = Field(
        0.01, ge=0, description="Part of the distance noise's sd proportional to the distance."
    )
    angular_jitter: float = Field(
        0.1, ge=0, description="Sd of each beam's true direction about the reported one, degrees."
    )
    dropout: float = Field(0.01, ge=0, le=1, description="Chance that a beam returns nothing.")
    motion_skew: bool = Field(
        True, description="Take a scan over one revolution of simulated time (False: at once)."
    )
    point_color: Color = Field((220, 0, 220), description="RGB colour of the drawn points.")

    def problems(self) -> list[tuple[str, str]]:
        """``max_range`` not above ``min_range``, or too many beams, as (key, message) pairs."""
        found = []
        if self.max_range <= self.min_range:
            found.append(
                (
                    "max_range",
                    f"must be greater than min_range ({self.min_range:g}), got {self.max_range:g}",
                )
            )
        if self.beams > MAX_BEAMS:
            found.append(
                (
                    "beams",
                    f"must be at most {MAX_BEAMS} (MAX_BEAMS), got {self.beams}: a whole scan is "
                    "read in one message of at most 1,000 commands",
                )
            )
        return found

    def noise_keys(self) -> list[str]:
        """The noise settings in effect that are not zero (``simmer check``'s summary)."""
        names = ("range_error", "range_error_proportional", "angular_jitter", "dropout")
        return [name for name in names if getattr(self, name)]


class Lidar(Device):
    """A spinning 2D LiDAR modelled on the RPLidar A1M8, a whole scan a revolution: ``l0-A``
    reads the beam at A degrees (0: none returned), ``l0--1`` the beams, ``l0--2`` the scan's
    number (docs/protocol.md)."""

    Params = LidarParams
    default_outline: ClassVar[FloatArray] = rectangle(2.8, 3.8)

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, LidarParams)
        self.settings = params
        n = params.beams
        self.period = 1.0 / params.scan_rate
        self.directions: FloatArray = np.arange(n, dtype=np.float64) * (360.0 / n)
        """Each beam's nominal angle, degrees clockwise from the LiDAR's front."""
        self.mount = np.array([self.position.x, self.position.y, self.rotation])
        self.distances: FloatArray = np.zeros(n)
        """The latest scan's readings, inches (0: no return)."""
        self._readings: list[float] | None = None
        """The latest scan's distances as a list, made at its first read: a whole-scan read
        indexes it 360 times, which a list does three times as fast as an array."""
        self._beam_of = {float(angle): k for k, angle in enumerate(self.directions)}
        """Each beam's index by its nominal angle, which a whole-scan read names exactly."""
        self.points: FloatArray = np.full((n, 2), math.nan)
        """Where each beam of the latest scan met something, world inches (NaN: no return)."""
        self.number = 0
        """The latest scan's number: 1 the one made at the start pose, then one a revolution."""
        self.scan_time = 0.0
        """When the latest scan ended, simulated seconds."""
        self.vectors = beam_vectors(self.directions, self.rotation)
        """Each beam's unit vector (2, beams: x row, y row) at robot heading 0, the mount's
        rotation included: a scan turns them by the robot's heading."""
        self._track: list[float] = []
        """The revolution under way's steps, flat (time, x, y, heading, time, ...; the heading
        as the robot has it, in [0, 360): the kernel unwraps it): a list appended to each step
        and made an array once a scan, the cheapest way per step."""
        self._state = np.array(
            [
                0.0,  # the maze's cell, the block seen: set at the first scan
                0.0,
                self.period,
                0.0,  # the revolution's end: set each scan
                float(params.motion_skew),
                self.position.x,
                self.position.y,
                params.min_range,
                params.max_range,
                params.range_error,
                params.range_error_proportional,
                params.dropout,
                math.radians(params.angular_jitter),
                -1.0,  # where this revolution's normals start (-1: that noise is off): set
                -1.0,  # at each draw, moved on a revolution by the kernel
                -1.0,  # the next gap between dropped beams; the beams before the next drop
                0.0,
            ]
        )
        """:func:`~simmer.geometry.scan_revolution`'s numbers, in one array (each argument of
        a compiled call costs), each written only when it changes (a write costs too)."""
        ranged = bool(params.range_error or params.range_error_proportional)
        self._rows = (bool(params.angular_jitter), ranged)
        """Which rows of standard normals a revolution draws: its beams' jitter, their range
        error."""
        rows = sum(self._rows)
        self._normals = np.zeros(NOISE_SCANS * rows * n if rows else 1)
        """The normals of NOISE_SCANS revolutions, drawn at once from the device's stream:
        NumPy's call costs as much as a few hundred of its draws."""
        self._gaps = np.zeros(NOISE_SCANS * n if params.dropout else 1)
        """The beams from one dropped beam to the next (geometric draws, the chance
        ``dropout``: each beam dropped independently, as a uniform draw a beam would make it,
        for a draw a dropped beam), drawn when fewer than a revolution's beams are left."""
        self._drawn = NOISE_SCANS
        """Revolutions of the drawn noise used (NOISE_SCANS: none left)."""
        self._gaps_left = len(self._gaps) - n
        """The index of ``_gaps`` past which fewer than a revolution's gaps are left."""
        self._due = self.period - 1e-9
        """When the revolution under way ends (a hair early: steps' times are sums)."""

    def height(self, world: World) -> float:
        """The scan plane's height: ``height``, else the third position value, else the
        robot's height."""
        if self.settings.height is not None:
            return self.settings.height
        return self.mount_height if self.mount_height is not None else world.robot.height

    def sees_block(self, world: World) -> bool:
        """A scan plane below the block's top meets the block."""
        return self.height(world) < world.block.size

    # -- stepping ------------------------------------------------------------------------

    def _record(self, world: World) -> float:
        """Keep the robot's pose now, and the first scan (at the start pose) if none is made
        yet; the time now (:meth:`update` does the same, written out)."""
        track = self._track
        if not track:
            self._first(world)
        now = world.time
        if now > track[-4]:
            track.append(now)
            track += world.robot.pose
        return now

    def _first(self, world: World) -> None:
        """The first pose recorded and the scan the spinning LiDAR made there before the run
        began (the start pose's, if the run has begun)."""
        start = world.robot.start_pose if world.time > 0.0 else world.robot.pose
        self._track.append(0.0)
        self._track += start
        state = self._state
        state[0] = world.maze.cell
        state[1] = self.sees_block(world)
        state[4] = 0.0  # the scan before the run: the robot stood still
        self._scan(world, 0.0)
        state[4] = float(self.settings.motion_skew)

    def update(self, world: World) -> None:
        """Record this step's pose; cast every scan whose revolution has ended."""
        # _record's body without its check, written out: called every step, and a call
        # costs about a third of it.
        track = self._track
        if not track:
            self._first(world)
        now = world.time  # later than any pose kept: a step's time grows, a read's does not
        track.append(now)
        track += world.robot.pose  # its heading as the robot has it: the kernel unwraps
        if now >= self._due:
            self._revolve(world, now)

    def _revolve(self, world: World, now: float) -> None:
        """Cast every revolution ended by ``now``; drop the poses before the revolution under
        way (the one before it stays)."""
        kept = 0
        while now >= self._due:
            kept = self._scan(world, self.scan_time + self.period)
        if kept:
            del self._track[: 4 * kept]

    def _scan(self, world: World, end: float) -> int:
        """Cast the revolution ending at ``end`` and apply its noise (see the module doc); the
        poses no longer needed (:func:`~simmer.geometry.scan_revolution`). Python's part is
        kept to what changes: the end, the noise drawn when it runs out."""
        state = self._state
        if self._drawn == NOISE_SCANS:
            self._draw()
        self._drawn += 1
        if self.settings.dropout and not 0.0 <= state.item(15) <= self._gaps_left:
            self._gaps[:] = self.rng.geometric(self.settings.dropout, len(self._gaps))
            if state[15] < 0.0:  # the first: the beams before the first drop
                state[16] = self._gaps[0] - 1.0
                state[15] = 1.0
            else:
                state[15] = 0.0
        state[3] = end
        maze = world.maze
        kept: int = scan_revolution(
            maze.hwall,
            maze.vwall,
            maze.segments,
            world.block.segments,
            np.array(self._track, dtype=np.float64),  # the dtype given: twice as fast
            state,
            self.vectors,
            self._normals,
            self._gaps,
            self.distances,
            self.points,
        )
        self._readings = None
        self.number += 1
        self.scan_time = end
        self._due = end + self.period - 1e-9
        return kept

    def _draw(self) -> None:
        """Draw the next NOISE_SCANS revolutions' normals (only the rows configured: a
        revolution's jitter's, then its range error's); the kernel moves on a revolution a
        scan."""
        jitter, ranged = self._rows
        if jitter or ranged:
            standard_normals(self.rng, self._normals)
            self._state[13] = 0.0 if jitter else -1.0
            self._state[14] = self.settings.beams * jitter if ranged else -1.0
        self._drawn = 0

    # -- reading -------------------------------------------------------------------------

    def simulate(self, value: float, world: World) -> float:
        """A beam's distance of the latest scan (``value``: its angle, 0 to 360 degrees), or
        -1: the beams per revolution, -2: the scan's number."""
        self._record(world)
        beam = self._beam_of.get(value)
        if beam is None:
            if value == BEAMS_READ:
                return float(self.settings.beams)
            if value == SCAN_NUMBER_READ:
                return float(self.number)
            if not 0.0 <= value < 360.0:
                raise CommandError(
                    f"a LiDAR reads the beam at an angle from 0 to 360 degrees, or -1 (the beams "
                    f"per revolution) or -2 (the scan's number); {value:g} is none of them"
                )
            n = self.settings.beams
            beam = round(value * n / 360.0) % n
        readings = self._readings
        if readings is None:
            readings = self._readings = self.distances.tolist()
        return readings[beam]

    def shapes(self, world: World) -> list[Shape]:
        """The latest scan's points, while recent enough to show."""
        s = self.settings
        if not s.visible_measurement or world.time - self.scan_time > s.visible_measurement_time:
            return []
        color = s.point_color
        return [
            Circle(Vec2(float(x), float(y)), 0.35, color)
            for x, y in self.points
            if not math.isnan(x)
        ]
