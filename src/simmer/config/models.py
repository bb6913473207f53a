"""Typed, frozen configuration models.

The native file is TOML with SimMeR's own key names at the top level (so the lab manual's names
still apply: ``robot_start_position``, ``walls``, ``frame_rate``...) and one table per device::

    [sensors.u0]
    type = "ultrasonic"
    position = [0, 2.5]

The table name is the device id. Motors default to ``type = "motor"``, drives to
``type = "drive"``; sensors must say what they are.
"""

from __future__ import annotations

import codecs
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from pydantic import BaseModel, Field, ValidationInfo, field_validator

from simmer.config.link import LinkSettings
from simmer.config.project import (
    GenerateSettings,
    ScenarioSettings,
    ScoreSettings,
    ZoneSettings,
)
from simmer.devices.base import SETTINGS_CONFIG, Color, DeviceParams, Whole
from simmer.devices.registry import DeviceKinds
from simmer.errors import ConfigIssue
from simmer.ports import PORT_RX, PORT_TX
from simmer.protocol import FramedCodec, PackedCodec, ReplyCodec

Point = tuple[float, float]

SIMMER_DEFAULT_WALLS: tuple[tuple[int, ...], ...] = (
    (3, 3, 1, 1, 0, 2, 0, 2),
    (3, 3, 0, 1, 1, 1, 1, 1),
    (1, 0, 2, 0, 0, 1, 0, 1),
    (1, 1, 1, 1, 1, 1, 0, 2),
)

MAX_CELLS_PER_SIDE = 500
"""Rows, and cells in a row, of ``walls`` (the lab maze is 4 rows of 8): every wall is stored
and drawn, and a reading walks the maze cell by cell. A 500 x 500 maze builds and steps in
0.4 s and 164 MB; the original SimMeR built 160 x 320 (in 23 s and 1.4 GB). Its drawing is
bounded by :data:`MAX_DRAWING_PIXELS` (lower ``ppi`` for a large maze)."""
MAX_FLOOR_TILES = 1_000_000
"""Floor tiles over the whole maze (the lab maze has 512): the pattern is drawn from one array
of random numbers, 8 bytes a tile."""
MAX_DRAWING_PIXELS = 16_384
"""Pixels a side of the maze drawing (maze size x ``ppi`` + 2 x ``border_pixels``; the lab's is
1,576 x 808): the largest image most graphics cards draw. The window scales to the screen."""
MAX_PPI = 200.0
"""Window pixels per inch: more than any screen shows (a 27-inch 4K screen has 163)."""
MAX_LINE_WIDTH = 12.0
"""Inches: a drawn outline wider than a lab maze cell would hide the maze."""
MAX_TIMEOUT = 86_400.0
"""Seconds (a day): longer than any lab session; waits of centuries overflow the system's
timers."""

Group = Literal["motors", "drives", "sensors"]
"""The configuration table a device lives in."""
DEVICE_GROUPS: tuple[Group, ...] = ("motors", "drives", "sensors")


class Settings(BaseModel):
    """Every scalar setting of a configuration (BEHAVIOUR §8) plus SimMeR 2 additions."""

    model_config = SETTINGS_CONFIG

    # Control
    rand_error: bool = Field(False, description="True: fresh random noise every run.")
    rand_bias: bool = Field(False, description="True: draw each drive's bias once at start.")
    bias_strength: tuple[float, float] = Field(
        (0.02, 0.2),
        description="Standard deviations of the drawn bias: [linear, rotational].",
    )
    seed: Whole | None = Field(
        None, ge=0, description="Noise seed when rand_error is false (default: floor_seed)."
    )
    protocol: Literal["packed", "framed"] = Field(
        "packed",
        description="What the two-port scheme and the serial port speak: 'packed' floats "
        "(SimMeR v1.0/v1.1, the Arduino examples) or 'framed' text, [u0] -> [u0:15.45] "
        "(SimMeR v1.2). The persistent protocol always sends packed frames.",
    )
    reply_bytes: Literal[4, 8] = Field(
        4, description="Packed reply width: 4 (float32, SimMeR v1.1, Arduino) or 8 (float64, v1.0)."
    )
    frame_start: str = Field("[", description="Framed protocol: the character opening a frame.")
    frame_end: str = Field("]", description="Framed protocol: the character closing a frame.")
    round_digits: Whole = Field(
        3, ge=0, le=15, description="Framed protocol: decimals of a reading in a reply."
    )
    lenient_commands: bool = Field(
        False,
        description="Read commands as the original SimMeR did: skip the third character "
        "whatever it is, read an unreadable value as 0 (logged once). On by itself for a "
        "SimMeR config.py; off: such commands answer NaN.",
    )
    plugins: tuple[str, ...] = Field(
        (), description="Python files or modules that register device kinds of your own."
    )
    # Network
    host: str = Field("127.0.0.1", description="Address to listen on (this machine only).")
    port_rx: Whole = Field(PORT_RX, ge=1, le=65535, description="SimMeR TCP: commands arrive here.")
    port_tx: Whole = Field(PORT_TX, ge=1, le=65535, description="SimMeR TCP: replies leave here.")
    timeout: float = Field(
        300.0,
        gt=0,
        le=MAX_TIMEOUT,
        description="Seconds (at most a day) a serial reply, a connection that has not sent a "
        "whole message, or an uncollected two-port reply may wait before it is given up.",
    )
    idle_timeout: float = Field(
        3600.0,
        gt=0,
        le=MAX_TIMEOUT,
        description="Seconds (at most a day) a persistent connection may stay open between "
        "messages before it is closed (a program sitting at a prompt keeps its connection "
        "for an hour).",
    )
    str_encoding: str = Field("utf-8", description="Text encoding of commands.")
    link: LinkSettings = Field(
        LinkSettings(),
        description="How the link to the robot behaves (docs/link.md); off by default.",
    )
    # Block
    block_position: Point = Field((66.0, 5.0), description="Block centre [x, y], inches.")
    block_rotation: float = Field(0.0, description="Block rotation, degrees from +y.")
    block_size: float = Field(3.0, gt=0, description="Block side and height, inches.")
    # Robot
    robot_start_position: Point = Field((6.0, 42.0), description="Start [x, y], inches.")
    robot_start_rotation: float = Field(180.0, description="Start heading, degrees from +y.")
    robot_width: float = Field(6.0, gt=0, description="Side of the default square outline.")
    robot_height: float = Field(6.0, gt=0, description="Tallest point of the robot, inches.")
    robot_outline: tuple[Point, ...] | None = Field(
        None, min_length=3, description="Polygon [[x, y], ...] in the robot frame, inches."
    )
    # Maze
    maze: str | GenerateSettings | None = Field(
        None,
        description="A maze of its own (docs/mazes.md): a maze file (.toml, or a .txt "
        "picture) relative to the configuration, a course maze's name ('mie444'), or a "
        "[maze] table generating one from a seed; it supplies walls, wall_segment_length, "
        "floor_segment_length, floor_seed and the zones' cells (a setting written here wins).",
    )
    wall_segment_length: float = Field(12.0, gt=0, description="Side of a maze cell, inches.")
    floor_segment_length: float = Field(
        3.0,
        gt=0,
        description=f"Side of a floor tile, inches (at most {MAX_FLOOR_TILES:,} tiles in all).",
    )
    walls: tuple[tuple[Whole, ...], ...] = Field(
        SIMMER_DEFAULT_WALLS,
        description="Cell matrix, first row on top; 0 = solid, else floor "
        f"(at most {MAX_CELLS_PER_SIDE} x {MAX_CELLS_PER_SIDE}).",
    )
    floor_seed: Whole = Field(
        5489, ge=0, lt=2**32, description="Floor pattern seed; 5489 is the lab maze's."
    )
    # Graphics
    frame_rate: float = Field(60.0, gt=0, le=10000, description="Simulation steps per second.")
    ppi: float = Field(
        16.0,
        gt=0,
        le=MAX_PPI,
        description=f"Window pixels per inch (at most {MAX_PPI:g}; the maze drawing is at most "
        f"{MAX_DRAWING_PIXELS:,} pixels a side).",
    )
    border_pixels: Whole = Field(20, ge=0, description="Window border around the maze, pixels.")
    background_color: Color = Field((43, 122, 120), description="Window background RGB.")
    wall_thickness: float = Field(
        0.25,
        ge=0,
        le=MAX_LINE_WIDTH,
        description=f"Drawn wall width, inches (at most {MAX_LINE_WIDTH:g}).",
    )
    wall_color: Color = Field((255, 0, 0), description="Wall RGB.")
    robot_thickness: float = Field(
        0.25,
        ge=0,
        le=MAX_LINE_WIDTH,
        description=f"Drawn robot outline width, inches (at most {MAX_LINE_WIDTH:g}).",
    )
    robot_color: Color = Field((0, 0, 255), description="Robot outline RGB.")
    block_thickness: float = Field(
        0.25,
        ge=0,
        le=MAX_LINE_WIDTH,
        description=f"Drawn block outline width, inches (at most {MAX_LINE_WIDTH:g}).",
    )
    block_color: Color = Field((127, 127, 20), description="Block RGB.")
    # Project (docs/project.md)
    zones: ZoneSettings = Field(ZoneSettings(), description="Named areas of the maze.")
    scenario: ScenarioSettings = Field(
        ScenarioSettings(), description="Start, block place and target zone of a run."
    )
    score: ScoreSettings = Field(ScoreSettings(), description="The project's scoring rubric.")
    # Debug
    simulate_list: tuple[str, ...] = Field(
        (), description="Sensor ids read every step, so their measurement is always drawn."
    )

    def run_seed(self, seed: int | None = None) -> int:
        """The noise seed of a run: ``seed`` if given; else a fresh one each run if
        ``rand_error``; else ``seed`` from the settings, or ``floor_seed`` if none is given.
        The one place that decides it (the simulation and its summary both ask)."""
        if seed is not None:
            return seed
        if self.rand_error:
            return int(np.random.SeedSequence().entropy)  # type: ignore[arg-type]
        return self.floor_seed if self.seed is None else self.seed

    @field_validator("bias_strength")
    @classmethod
    def _non_negative_strength(cls, value: tuple[float, float]) -> tuple[float, float]:
        if min(value) < 0:
            raise ValueError("both strengths must be 0 or more")
        return value

    @field_validator("frame_start", "frame_end")
    @classmethod
    def _frame_character(cls, value: str, info: ValidationInfo) -> str:
        if len(value) != 1 or not value.isascii() or not value.isprintable() or value in ",:- ":
            raise ValueError(
                f"must be one printable ASCII character other than , : - and space, "
                f"not {value!r}; SimMeR v1.2 uses '[' and ']'"
            )
        if info.field_name == "frame_end" and value == info.data.get("frame_start"):
            raise ValueError(
                f"frame_start is {value!r} too; the two must differ (SimMeR v1.2 uses '[' and ']')"
            )
        return value

    @field_validator("str_encoding")
    @classmethod
    def _known_encoding(cls, value: str) -> str:
        """A text encoding that writes the protocol's ASCII as ASCII, both ways: commands,
        frames and replies are ASCII text. ``rot13`` and ``hex`` are not text encodings (the
        first message would fail); ``utf-16`` and ``utf-32`` turn every command into NaN."""
        try:
            info = codecs.lookup(value)
        except LookupError:
            raise ValueError(f"unknown text encoding {value!r}; use 'utf-8' or 'ascii'") from None
        sample = "".join(map(chr, range(32, 127))) + "\r\n"  # every printable ASCII character
        try:
            carries = info._is_text_encoding and sample.encode(value).decode(value) == sample
            carries = carries and sample.encode(value) == sample.encode("ascii")
        except (UnicodeError, LookupError):
            carries = False
        if not carries:
            raise ValueError(
                f"{value!r} cannot carry the protocol, whose commands are ASCII text; "
                "use 'utf-8' or 'ascii'"
            )
        return value

    @field_validator("background_color", "wall_color", "robot_color", "block_color", mode="after")
    @classmethod
    def _rgb(cls, value: Color) -> Color:
        if any(not 0 <= c <= 255 for c in value):
            raise ValueError("each colour value must be between 0 and 255")
        return value


@dataclass(frozen=True)
class DeviceSpec:
    """One configured device: its id, table (group), registered kind and validated settings."""

    id: str
    group: Group
    kind: str
    params: DeviceParams


@dataclass(frozen=True)
class SimConfig:
    """A whole validated configuration: settings plus devices, and where it came from.

    ``warnings`` are what a native file may not have but an original SimMeR ``config.py`` did
    and still runs (a hidden block, an arc drive...); the loader collects them, the CLI prints
    them.
    """

    settings: Settings
    devices: tuple[DeviceSpec, ...]
    source: str = "<built-in default>"
    warnings: tuple[ConfigIssue, ...] = ()
    origin: str = ""
    """For an original ``config.py``: which release it looks like and what that means for the
    replies (said at start: "looks like a SimMeR v1.0 config: replies are 8-byte doubles...")."""
    kinds: DeviceKinds = field(default_factory=DeviceKinds)
    """The device kinds this configuration uses: the process-wide ones and its plug-ins' own."""

    def reply_codec(self) -> ReplyCodec:
        """What the two-port scheme and the serial port speak, from the ``protocol`` setting."""
        s = self.settings
        lenient = s.lenient_commands
        if s.protocol == "packed":
            return PackedCodec(s.reply_bytes, s.str_encoding, lenient)
        categories = {spec.id: spec.group[:-1] for spec in self.devices}
        return FramedCodec(
            categories, s.frame_start, s.frame_end, s.round_digits, s.str_encoding, lenient
        )

    def device(self, device_id: str) -> DeviceSpec:
        """The device with this id (KeyError if none)."""
        for spec in self.devices:
            if spec.id == device_id:
                return spec
        raise KeyError(device_id)
