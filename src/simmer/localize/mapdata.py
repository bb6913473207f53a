"""The maze as a control program may know it: walls, sizes, floor, zones, start and every
device's mount, as plain JSON-able data (``robot.maze()``, ``simmer export-map``).

What a program may *not* know is left out: the drawn start pose of a random start, the block's
drawn place and the drawn target (the configured start is given only when it is fixed).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from simmer.config.maze import robot_outline
from simmer.config.project import GenerateSettings
from simmer.devices.lidar import Lidar
from simmer.devices.motion import Encoder
from simmer.devices.sensors import Infrared, Ultrasonic
from simmer.devices.tof import TimeOfFlight

if TYPE_CHECKING:
    from simmer.devices.base import Device
    from simmer.world.simulation import Simulation

MAP_VERSION = 1
"""Bumped when a key changes meaning (new keys may be added without it)."""


FRAME = (
    ("x", "inches, to the right in the window, from the maze's left edge"),
    ("y", "inches, down the window, from the maze's top edge (row 0 at y = 0)"),
    ("heading", "degrees from +y: 0 faces +y (down), 90 faces -x (left), 180 -y, 270 +x"),
    ("positive_turn", "the heading grows: clockwise as the window shows it (y grows downward)"),
    ("move", "d inches at heading h: dx = -d sin h, dy = d cos h"),
    ("robot_frame", "+y forward, +x the robot's left"),
)
"""The coordinate frame in words, key by key (the map's ``frame``): the same words as the
docs' (README's Coordinates), so that a program reading the map needs no screenshot."""


def _rounded(values: Any) -> list[float]:
    return [round(float(v), 6) for v in values]


def device_mount(device: Device, sim: Simulation) -> dict[str, Any]:
    """Where a device sits on the robot and what it senses (robot frame, inches, degrees)."""
    mount: dict[str, Any] = {
        "id": device.id,
        "kind": type(device).kind or device.params.type,
        "category": device.category,
        "position": _rounded(device.position),
        "rotation": float(device.rotation),
        "height": device.mount_height,
    }
    if isinstance(device, Ultrasonic):
        s = device.settings
        mount.update(
            height=device.height(sim),
            beamwidth=s.beamwidth,
            min_range=s.min_range,
            max_range=s.max_range,
            num_rays=s.num_rays,
        )
    elif isinstance(device, Lidar):
        scanner = device.settings
        mount.update(
            height=device.height(sim),
            beams=scanner.beams,
            scan_rate=scanner.scan_rate,
            min_range=scanner.min_range,
            max_range=scanner.max_range,
        )
    elif isinstance(device, TimeOfFlight):
        mount.update(
            height=device.height(sim),
            fov=device.fov,
            max_range=device.max_range,
            num_rays=device.settings.num_rays,
            out_of_range=device.out_of_range,
            units=device.settings.units,
        )
    elif isinstance(device, Encoder):
        e = device.settings
        mount.update(
            wheel=e.wheel,
            track_width=e.track_width,
            wheel_diameter=e.wheel_diameter,
            counts_per_rev=e.counts_per_rev,
        )
    elif isinstance(device, Infrared):
        floor = device.settings
        mount.update(radius=device.radius, fov=floor.fov, threshold=floor.threshold)
        if mount["height"] is None:
            mount["height"] = floor.height
    return mount


def _maze_setting(maze: str | GenerateSettings | None) -> str | dict[str, Any] | None:
    """The configuration's ``maze`` as it would be written (a file, a course maze's name, the
    generator's table) or None for inline walls: a program given the configuration file can
    build the same maze with ``maze`` as an override (a sweep over mazes)."""
    if maze is None or isinstance(maze, str):
        return maze
    return maze.model_dump(mode="json")


def map_data(sim: Simulation) -> dict[str, Any]:
    """Everything a program may know of the world before it moves (see the module doc).

    ``walls``: the configuration's matrix, row 0 at y = 0 (0 = solid cell); ``wall_segments``:
    every wall as [x1, y1, x2, y2]; ``floor``: one string per tile row, ``1`` white, ``0`` black.
    """
    settings = sim.config.settings
    maze = sim.maze
    zones = sim.zones
    spec = settings.scenario.start
    fixed = spec not in ("random", "open")
    start = sim.robot.start_pose if fixed else None
    return {
        "version": MAP_VERSION,
        "units": "inches; degrees from +y, growing clockwise in the window (y down)",
        "frame": dict(FRAME),
        "walls": [list(row) for row in settings.walls],
        "maze": _maze_setting(settings.maze),
        "rows": maze.rows,
        "cols": maze.cols,
        "cell_size": maze.cell,
        "width": maze.width,
        "height": maze.height,
        "wall_segments": [_rounded(segment) for segment in maze.segments],
        "floor_tile": maze.tile,
        "floor": ["".join("1" if white else "0" for white in row) for row in maze.floor_white],
        "zones": {
            "convention": zones.convention,
            "loading": [list(c) for c in zones.loading.cells] if zones.loading else [],
            "dropoff": {name: [list(c) for c in z.cells] for name, z in zones.dropoff.items()},
            "start": [list(c) for c in zones.start],
        },
        "start": {
            "spec": spec,
            "pose": _rounded(start) if start is not None else None,
        },
        "robot": {
            "outline": [_rounded(p) for p in robot_outline(settings)],
            "height": settings.robot_height,
        },
        "block_size": settings.block_size,
        "devices": [device_mount(d, sim) for d in sim.robot.devices.values()],
    }
