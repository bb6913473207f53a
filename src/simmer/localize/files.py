"""Files for programs that also run on the real robot: the maze as JSON (``simmer
export-map``) and lookup tables of expected readings (``simmer table``)."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from simmer.geometry import FloatArray
from simmer.localize.mapdata import map_data
from simmer.world.expected import lidar_table as lidar_readings
from simmer.world.expected import table
from simmer.world.simulation import Simulation

TABLE_SUFFIXES = (".npz", ".csv")


def write_map(sim: Simulation, path: Path) -> None:
    """The maze as ``robot.maze()`` gives it, as JSON with a line per key."""
    data = map_data(sim)
    lines = [f" {json.dumps(key)}: {json.dumps(value)}" for key, value in data.items()]
    path.write_text("{\n" + ",\n".join(lines) + "\n}\n", encoding="utf-8")


def write_table(
    sim: Simulation,
    path: Path,
    step: float,
    headings: FloatArray,
    sensors: Sequence[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[int, list[str]]:
    """Compute a table (:func:`~simmer.world.expected.table`) and write it; how many
    readings, and the sensors.

    ``.npz``: ``readings[y, x, heading, sensor]`` (float32, NaN in solid cells), ``x``, ``y``,
    ``headings``, ``sensors``, ``step``. ``.csv``: a row per open position and heading,
    ``x,y,heading,`` then a column per sensor.
    """
    if path.suffix not in TABLE_SUFFIXES:
        raise ValueError(f"{path}: a table is written as .npz or .csv, not {path.suffix!r}")
    xs, ys, ids, readings = table(sim, step, headings, sensors, progress)
    if path.suffix == ".npz":
        np.savez(
            path,
            readings=readings.astype(np.float32),
            x=xs,
            y=ys,
            headings=headings,
            sensors=np.array(ids),
            step=step,
        )
    else:
        gy, gx, gh = np.meshgrid(ys, xs, headings, indexing="ij")
        rows = np.column_stack((gx.ravel(), gy.ravel(), gh.ravel(), readings.reshape(-1, len(ids))))
        rows = rows[~np.isnan(rows[:, 3:]).any(axis=1)] if ids else rows
        with path.open("w", encoding="utf-8") as file:
            file.write(",".join(["x", "y", "heading", *ids]) + "\n")
            np.savetxt(file, rows, fmt="%.6g", delimiter=",")
    return int(readings.size), ids


def lidar_table(
    sim: Simulation,
    step: float,
    sensor: str,
    path: Path | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> int:
    """Compute a LiDAR's table (:func:`~simmer.world.expected.lidar_table`), write it if
    ``path`` is given, and say how many readings it holds.

    ``.npz``: ``readings[y, x, beam]`` (float32), ``x``, ``y``, ``angles`` (each beam's
    heading, degrees), ``sensors`` (the LiDAR's id), ``step``. ``.csv``: a row per open
    position, ``x,y,`` then a column per beam (``b0``, ``b1``...).
    """
    if path is not None and path.suffix not in TABLE_SUFFIXES:
        raise ValueError(f"{path}: a table is written as .npz or .csv, not {path.suffix!r}")
    xs, ys, readings = lidar_readings(sim, step, sensor, progress)
    angles = np.arange(readings.shape[2], dtype=np.float64) * (360.0 / readings.shape[2])
    if path is not None and path.suffix == ".npz":
        np.savez(
            path,
            readings=readings.astype(np.float32),
            x=xs,
            y=ys,
            angles=angles,
            sensors=np.array([sensor]),
            step=step,
        )
    elif path is not None:
        gy, gx = np.meshgrid(ys, xs, indexing="ij")
        rows = np.column_stack((gx.ravel(), gy.ravel(), readings.reshape(-1, len(angles))))
        rows = rows[~np.isnan(rows[:, 2:]).any(axis=1)]
        with path.open("w", encoding="utf-8") as file:
            file.write(",".join(["x", "y", *(f"b{k}" for k in range(len(angles)))]) + "\n")
            np.savetxt(file, rows, fmt="%.6g", delimiter=",")
    return int(readings.size)
