"""The maze's zones, worked out from a configuration (see :mod:`simmer.config.project`)."""

from __future__ import annotations

from dataclasses import dataclass

from simmer.config.models import Settings, SimConfig
from simmer.config.project import Cell


@dataclass(frozen=True)
class Zone:
    """A named group of cells."""

    name: str
    cells: tuple[Cell, ...]

    def contains(self, x: float, y: float, cell: float) -> bool:
        """True if the point (inches) lies in one of the zone's cells (edges included)."""
        for row, col in self.cells:
            if col * cell <= x <= (col + 1) * cell and row * cell <= y <= (row + 1) * cell:
                return True
        return False

    def describe(self) -> str:
        """``B1 [0, 5]`` or ``loading [0, 0] [0, 1] ...``."""
        return f"{self.name} " + " ".join(f"[{r}, {c}]" for r, c in self.cells)


@dataclass(frozen=True)
class Zones:
    """The loading zone, the drop-off zones by name and the start cells of one maze."""

    convention: str
    loading: Zone | None
    dropoff: dict[str, Zone]
    start: tuple[Cell, ...]
    cell: float

    @classmethod
    def from_settings(cls, settings: Settings) -> Zones:
        """Zones named outright in ``[zones]``, else from the walls codes by the convention."""
        z = settings.zones
        walls = settings.walls
        codes: dict[int, list[Cell]] = {}
        for r, row in enumerate(walls):
            for c, code in enumerate(row):
                codes.setdefault(code, []).append((r, c))
        open_cells = [cell for code, cells in sorted(codes.items()) if code for cell in cells]
        open_cells.sort()
        loading: tuple[Cell, ...] = ()
        dropoff: dict[str, tuple[Cell, ...]] = {}
        start: tuple[Cell, ...] = ()
        if z.convention == "project":
            loading = tuple(codes.get(3, ()))
            dropoff = {f"B{i + 1}": (cell,) for i, cell in enumerate(codes.get(2, ()))}
        elif z.convention == "lab2023":
            loading = tuple(codes.get(2, ()))
            groups = _connected(codes.get(3, []))
            dropoff = {f"D{i + 1}": group for i, group in enumerate(groups)}
            start = tuple(codes.get(3, ()))
        if z.loading is not None:
            loading = z.loading
        if z.dropoff is not None:
            dropoff = dict(z.dropoff)
        taken = set(loading) | {cell for cells in dropoff.values() for cell in cells}
        if z.start is not None:
            start = z.start
        elif not start:
            start = tuple(cell for cell in open_cells if cell not in taken)
        return cls(
            convention=z.convention,
            loading=Zone("loading", tuple(loading)) if loading else None,
            dropoff={name: Zone(name, cells) for name, cells in dropoff.items()},
            start=start,
            cell=settings.wall_segment_length,
        )

    def all(self) -> list[Zone]:
        """Every zone, the loading zone first."""
        return ([self.loading] if self.loading else []) + list(self.dropoff.values())

    def dropoff_at(self, x: float, y: float) -> str | None:
        """The name of the drop-off zone the point lies in, if any."""
        for name, zone in self.dropoff.items():
            if zone.contains(x, y, self.cell):
                return name
        return None

    def in_loading(self, x: float, y: float) -> bool:
        """True if the point lies in the loading zone."""
        return self.loading is not None and self.loading.contains(x, y, self.cell)

    def describe(self) -> str:
        """One line for ``simmer check``."""
        if not self.loading and not self.dropoff:
            return f"Zones ({self.convention} convention): none."
        parts = [zone.describe() for zone in self.all()]
        return (
            f"Zones ({self.convention} convention): {'; '.join(parts)}; "
            f"{len(self.start)} start cells."
        )


def _connected(cells: list[Cell]) -> list[tuple[Cell, ...]]:
    """The 4-connected groups of ``cells``, each sorted, in reading order of their first."""
    left = set(cells)
    groups = []
    for first in sorted(cells):
        if first not in left:
            continue
        group, todo = [], [first]
        left.discard(first)
        while todo:
            r, c = todo.pop()
            group.append((r, c))
            for near in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
                if near in left:
                    left.discard(near)
                    todo.append(near)
        groups.append(tuple(sorted(group)))
    return groups


def project_run(config: SimConfig) -> bool:
    """True for a run of the course project: the robot has a gripper. Its outcome has the
    project's milestones and score, and its zones are drawn unless ``[zones] visible = false``;
    a Lab 1 run's outcome and pictures stay as they were."""
    return any(spec.kind == "gripper" for spec in config.devices)


def zones_shown(config: SimConfig) -> bool:
    """Whether pictures of this configuration draw its zones (see :func:`project_run`)."""
    visible = config.settings.zones.visible
    return project_run(config) if visible is None else visible
