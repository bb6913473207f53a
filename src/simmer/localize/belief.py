"""A control program's belief, as it shows it (``robot.show``): read, bounded and kept.

A belief is a JSON object with any of these keys (world inches, degrees from +y):

* ``particles``: ``[[x, y, heading, weight], ...]``, at most :data:`MAX_PARTICLES`; more are
  cut, keeping the heaviest.
* ``cells``: a grid of probabilities, ``[[p, ...], ...]`` row 0 at y = 0, drawn over the maze
  (its rows and columns spread over the maze's), at most :data:`MAX_CELLS` values.
* ``pose``: ``[x, y, heading]``, the estimate (also counted as a reported pose,
  :class:`~simmer.world.events.EstimateEvent`); ``ellipse``: ``[a, b, angle]``, its
  uncertainty's semi-axes in inches and the angle of ``a`` from +x in degrees.
* ``path``: ``[[x, y], ...]``, a planned path, at most :data:`MAX_PATH` points.
* ``labels``: ``[[x, y, "text"], ...]``, at most :data:`MAX_LABELS` of :data:`MAX_LABEL_CHARS`
  characters.
* ``points``: ``[[x, y], ...]``, points the program places in the world, at most
  :data:`MAX_POINTS`: a LiDAR scan where the program believes its beams met walls
  (``Scan.points``), or its own map's points.

What is cut (points over a bound, entries that are not finite numbers) is counted, never
silently lost: the count is the reply to the show message, is logged, and is kept in the
run's events. The same reader reads a belief back from a run folder, where a bad one is one
plain ``ValueError`` line.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from simmer.untrusted import parse_json
from simmer.world.events import BeliefEvent, Event, ResetEvent

MAX_PARTICLES = 2000
"""Particles per show message; the window draws 2,000 at its frame rate."""
MAX_CELLS = 4096
"""Probabilities in one cell grid (a 64 x 64 grid)."""
MAX_PATH = 1000
"""Points of a planned path."""
MAX_POINTS = 1000
"""World points (``points``) per show: a whole scan of up to 999 beams (``MAX_BEAMS``)."""
MAX_LABELS = 20
"""Labels per show message."""
MAX_LABEL_CHARS = 40
"""Characters of a label (longer ones are cut)."""
SHOWS_PER_SECOND = 10
"""Show messages kept per simulated second; more are dropped whole (and counted). Ten beliefs
a second is smooth to watch, and a recording grows by at most ~0.5 MB a simulated second
(2,000 particles a show), so its 256 MB hold eight minutes of that."""
ESTIMATES_PER_SECOND = 60
"""Reported poses kept per simulated second; more are dropped (and counted)."""
MAX_BELIEF_BYTES = 256 * 1024
"""Longest belief read back from a run folder's events (one at the bounds is ~60 KB)."""

Float32Array = NDArray[np.float32]
_EMPTY: Float32Array = np.empty((0, 4), dtype=np.float32)
_EMPTY.setflags(write=False)


def _frozen(array: NDArray[Any]) -> Float32Array:
    """Kept as float32, read-only: a replay holds every belief shown, in less memory than
    their JSON took in the run's events (which a recording's size limit bounds)."""
    kept = array.astype(np.float32)
    kept.setflags(write=False)
    return kept


@dataclass(frozen=True)
class Belief:
    """One shown belief, within the bounds (see the module doc); arrays are read-only."""

    particles: Float32Array = field(default_factory=lambda: _EMPTY)
    """(N, 4) float32: x, y, heading, weight (weights scaled so the heaviest is 1)."""
    cells: Float32Array | None = None
    """(rows, cols) probabilities scaled so the largest is 1."""
    pose: tuple[float, float, float] | None = None
    ellipse: tuple[float, float, float] | None = None
    path: Float32Array = field(default_factory=lambda: _EMPTY[:, :2])
    labels: tuple[tuple[float, float, str], ...] = ()
    points: Float32Array = field(default_factory=lambda: _EMPTY[:, :2])
    """(N, 2) float32: world points (a scan placed by the program, map points)."""

    def to_json(self) -> str:
        """The belief as compact JSON (what a run's events keep): positions to 0.01 in,
        headings to 0.1 degree, weights and probabilities to 0.001 of the largest."""
        data: dict[str, Any] = {}
        if len(self.particles):
            p = self.particles.astype(np.float64)
            rounded = (np.round(p[:, :2], 2), np.round(p[:, 2], 1), np.round(p[:, 3], 3))
            data["particles"] = np.column_stack(rounded).tolist()
        if self.cells is not None:
            data["cells"] = np.round(self.cells.astype(np.float64), 3).tolist()
        if self.pose is not None:
            data["pose"] = [round(v, 3) for v in self.pose]
        if self.ellipse is not None:
            data["ellipse"] = [round(v, 3) for v in self.ellipse]
        if len(self.path):
            data["path"] = np.round(self.path.astype(np.float64), 2).tolist()
        if self.labels:
            data["labels"] = [[round(x, 3), round(y, 3), text] for x, y, text in self.labels]
        if len(self.points):
            data["points"] = np.round(self.points.astype(np.float64), 2).tolist()
        return json.dumps(data, separators=(",", ":"))


def _rows(value: Any, width: int, limit: int, name: str) -> tuple[NDArray[np.float64], int]:
    """``value`` as an (N, width) float array of finite rows, at most ``limit``... (cut count)."""
    if not isinstance(value, list):
        raise ValueError(f"{name} must be a list of [{', '.join(['number'] * width)}] rows")
    cut = max(0, len(value) - 4 * limit)  # never convert more than a few times the bound
    try:
        array = np.array(value[: 4 * limit], dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a list of rows of {width} numbers") from None
    if array.size == 0:
        return np.empty((0, width)), cut
    if array.ndim != 2 or array.shape[1] != width:
        raise ValueError(f"{name} must be a list of rows of {width} numbers")
    finite = np.isfinite(array).all(axis=1)
    cut += int((~finite).sum())
    return array[finite], cut


def _numbers(value: Any, count: int, name: str) -> tuple[float, ...]:
    if (
        not isinstance(value, list)
        or len(value) != count
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
        or not all(math.isfinite(v) for v in value)
    ):
        raise ValueError(f"{name} must be {count} finite numbers")
    return tuple(float(v) for v in value)


def _particles(value: Any) -> tuple[Float32Array, int]:
    """Particles within the bound (the heaviest kept), weights scaled to a largest of 1."""
    particles, cut = _rows(value, 4, MAX_PARTICLES, "particles")
    particles[:, 3] = np.clip(particles[:, 3], 0.0, None)
    if len(particles) > MAX_PARTICLES:
        keep = np.argpartition(-particles[:, 3], MAX_PARTICLES - 1)[:MAX_PARTICLES]
        cut += len(particles) - MAX_PARTICLES
        particles = particles[np.sort(keep)]
    top = particles[:, 3].max() if len(particles) else 0.0
    if top > 0:
        particles[:, 3] /= top
    return _frozen(particles), cut


def _cells(grid: Any) -> Float32Array:
    """A grid of probabilities (not finite or negative: 0), scaled to a largest of 1."""
    if not isinstance(grid, list) or not grid or not isinstance(grid[0], list):
        raise ValueError("cells must be a grid: a list of rows of probabilities")
    if len(grid) * len(grid[0]) > MAX_CELLS or len(grid) > MAX_CELLS:
        raise ValueError(f"cells: a grid of at most {MAX_CELLS} probabilities")
    try:
        cells = np.array(grid, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("cells must be rows of equal length, of numbers") from None
    if cells.ndim != 2:
        raise ValueError("cells must be rows of equal length, of numbers")
    cells = np.nan_to_num(cells, nan=0.0, posinf=0.0, neginf=0.0).clip(0.0, None)
    if cells.max() > 0:
        cells /= cells.max()
    return _frozen(cells)


def read_belief(data: Any) -> tuple[Belief, int]:
    """The belief in parsed JSON ``data`` and how many points were cut to fit the bounds;
    ValueError (one line) if ``data`` is not a belief."""
    if not isinstance(data, dict):
        raise ValueError('a belief is a JSON object such as {"particles": [[x, y, heading, w]]}')
    unknown = set(data) - {"particles", "cells", "pose", "ellipse", "path", "labels", "points"}
    if unknown:
        raise ValueError(
            f"unknown key {sorted(unknown)[0]!r} in a belief; the keys are particles, cells, "
            "pose, ellipse, path, labels and points"
        )
    particles, cut = _particles(data["particles"]) if "particles" in data else (_EMPTY, 0)
    cells = _cells(data["cells"]) if "cells" in data else None
    pose = _numbers(data["pose"], 3, "pose") if "pose" in data else None
    ellipse = _numbers(data["ellipse"], 3, "ellipse") if "ellipse" in data else None
    path = _EMPTY[:, :2]
    if "path" in data:
        points, cut_path = _rows(data["path"], 2, MAX_PATH, "path")
        cut += cut_path + max(0, len(points) - MAX_PATH)
        path = _frozen(points[:MAX_PATH])
    labels: list[tuple[float, float, str]] = []
    raw = data.get("labels", [])
    if not isinstance(raw, list):
        raise ValueError('labels must be a list of [x, y, "text"]')
    for entry in raw[:MAX_LABELS]:
        if not (isinstance(entry, list) and len(entry) == 3 and isinstance(entry[2], str)):
            raise ValueError('labels must be a list of [x, y, "text"]')
        x, y = _numbers(entry[:2], 2, "a label's x, y")
        labels.append((x, y, entry[2][:MAX_LABEL_CHARS]))
    cut += max(0, len(raw) - MAX_LABELS)
    shown = _EMPTY[:, :2]
    if "points" in data:
        placed, cut_points = _rows(data["points"], 2, MAX_POINTS, "points")
        cut += cut_points + max(0, len(placed) - MAX_POINTS)
        shown = _frozen(placed[:MAX_POINTS])
    belief = Belief(particles, cells, pose, ellipse, path, tuple(labels), shown)  # type: ignore[arg-type]
    return belief, cut


def parse_belief(text: str) -> tuple[Belief, int]:
    """:func:`read_belief` of JSON text (ValueError, one line, if it is not a belief)."""
    return read_belief(parse_json(text, "a belief", MAX_BELIEF_BYTES, "MAX_BELIEF_BYTES"))


class BeliefBoard:
    """An observer keeping the belief shown last (for the window, videos and replays); a
    reset clears it. A belief event that does not read (a hostile run folder) is skipped,
    and :attr:`bad` counts it."""

    def __init__(self) -> None:
        self.belief: Belief | None = None
        self.bad = 0
        self.first_problem = ""
        """Why the first belief that did not read did not."""

    def __call__(self, event: Event) -> None:
        if type(event) is BeliefEvent:
            try:
                self.belief = parse_belief(event.belief)[0]
            except ValueError as exc:
                self.bad += 1
                self.first_problem = self.first_problem or f"at {event.time:.2f} s: {exc}"
        elif isinstance(event, ResetEvent):
            self.belief = None
