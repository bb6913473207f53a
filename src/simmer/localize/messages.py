"""The persistent protocol's localization messages, answered in the loop thread.

``%maze`` (the maze as JSON, :func:`~simmer.localize.mapdata.map_data`), ``%show JSON`` (a
belief, :mod:`simmer.localize.belief`) and ``%pose X Y HEADING`` (the program's estimate).
They cost no simulated time, even in lockstep, and change nothing the simulation answers:
a show or pose becomes an event of its own (:data:`~simmer.world.events.SHOWN`), and only
within the bounds per simulated second; the rest is dropped and counted.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass

from simmer.geometry import Pose
from simmer.localize.belief import ESTIMATES_PER_SECOND, SHOWS_PER_SECOND, parse_belief
from simmer.localize.mapdata import map_data
from simmer.protocol import MAX_ABS_VALUE, decimal_number, printable
from simmer.world.events import BeliefEvent, EstimateEvent
from simmer.world.simulation import Simulation

log = logging.getLogger("simmer.localize")


@dataclass
class _Budget:
    """How many of one kind of message a simulated second keeps, and how many it dropped."""

    what: str
    """What is counted, for the log: ``show messages``, ``reported poses``."""
    per_second: int
    start: float = -math.inf
    used: int = 0
    dropped: int = 0
    """Dropped since the last one kept (reported with it)."""
    total_dropped: int = 0

    def take(self, now: float) -> bool:
        """Whether a message at simulated ``now`` is kept (False: dropped and counted)."""
        if not self.start <= now < self.start + 1.0:
            self.start, self.used = now, 0
        if self.used < self.per_second:
            self.used += 1
            return True
        if self.dropped == 0 or self.total_dropped % 1000 == 0:
            log.warning(
                "over %d %s a simulated second: the rest of this second's are dropped and "
                "counted (%d so far)",
                self.per_second,
                self.what,
                self.total_dropped + 1,
            )
        self.dropped += 1
        self.total_dropped += 1
        return False


class Localization:
    """Answers the localization messages of one simulation (see the module doc)."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.shows = _Budget("show messages", SHOWS_PER_SECOND)
        self.estimates = _Budget("reported poses", ESTIMATES_PER_SECOND)
        self.cut = 0
        """Points cut from kept beliefs to fit their bounds, in all."""

    def answer(self, text: str, client: str) -> tuple[list[float], str | None]:
        """The reply values, or the text, to one message; ValueError if it is none of them.

        ``%show``: one value, how many points were cut from it (0: all shown; -1: the whole
        message was dropped, over the bound per simulated second); ``%pose``: one value, 0 if
        kept, -1 if dropped; ``%maze``: the maze as JSON text.
        """
        word, _, rest = text[1:].partition(" ")
        if word == "maze" and not rest.strip():
            return [], json.dumps(map_data(self.sim), separators=(",", ":"))
        if word == "show":
            return [float(self.show(rest, client))], None
        if word == "pose":  # numbers as a command's (1_0 and ١٢ are not numbers there)
            parts = rest.split()
            values = [v for v in map(decimal_number, parts) if v is not None]
            if len(parts) != 3 or len(values) != 3:
                raise ValueError(
                    f"{printable(text[:60])!r}: write %pose X Y HEADING, three decimal numbers "
                    f"in ASCII digits within ±{MAX_ABS_VALUE:g} (MAX_ABS_VALUE)"
                )
            return [0.0 if self.estimate(Pose(*values), client) else -1.0], None
        raise ValueError(
            f"{printable(text[:60])!r} is not a localization message: '%maze', '%show JSON' "
            "or '%pose X Y HEADING'"
        )

    def show(self, text: str, client: str) -> int:
        """Keep a belief (within the bounds); how many points were cut (-1: all dropped)."""
        sim = self.sim
        if not self.shows.take(sim.time):
            return -1
        belief, cut = parse_belief(text)
        if cut:
            self.cut += cut
            log.warning(
                "%s: %d points of a shown belief cut to fit its bounds (see docs/localization.md)",
                printable(client),
                cut,
            )
        skipped, self.shows.dropped = self.shows.dropped, 0
        sim.emit(BeliefEvent(sim.time, belief.to_json(), cut, skipped, sim.steps, client))
        if belief.pose is not None:
            self.estimate(Pose(*belief.pose), client)
        return cut

    def estimate(self, pose: Pose, client: str) -> bool:
        """Keep a reported pose, with the truth beside it; False if over the bound."""
        sim = self.sim
        if not self.estimates.take(sim.time):
            return False
        sim.emit(EstimateEvent(sim.time, pose, sim.robot.pose, sim.steps, client))
        return True
