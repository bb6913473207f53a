"""Replay: a run's input events fed to a fresh simulation reproduce the run.

A run depends only on its configuration, its seed and its inputs (commands, manual keys,
placing the robot, resets: :data:`~simmer.world.events.INPUTS`), each applied at the step it
happened. What the program showed of its belief (:data:`~simmer.world.events.SHOWN`) is
passed on to the observers at its step, as it was shown. :func:`replay` applies them again
to a new simulation (:func:`feed`: to one made with observers of its own) and says where a
reply differs (a different SimMeR version, a changed device, a configuration that is not the
same).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from simmer.config.models import SimConfig
from simmer.world.events import (
    INPUTS,
    SHOWN,
    CommandEvent,
    Event,
    KeysEvent,
    Observer,
    PlaceEvent,
)
from simmer.world.simulation import Simulation


@dataclass
class Replayed:
    """The simulation after a replay, and every reply that came out differently."""

    sim: Simulation
    differences: list[str] = field(default_factory=list)


def _same(a: float, b: float) -> bool:
    """Bit for bit (so NaN equals NaN and 0.0 differs from -0.0)."""
    return (math.isnan(a) and math.isnan(b)) or struct.pack("<d", a) == struct.pack("<d", b)


def same_replies(a: Sequence[float], b: Sequence[float]) -> bool:
    """Whether two messages' replies are the same, value for value, bit for bit (NaN equal to
    NaN): what a replay must give back, and what the HUD counts as a repeat."""
    return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))


def replay(
    config: SimConfig,
    seed: int,
    events: Iterable[Event],
    observers: Iterable[Observer] = (),
    until_step: int | None = None,
) -> Replayed:
    """Feed the inputs among ``events`` to a fresh simulation at their steps (:func:`feed`).

    ``observers`` see the replayed run's events (a trace writer, a video).
    """
    sim = Simulation(config, seed=seed)
    for observer in observers:
        sim.add_observer(observer)
    return feed(sim, events, until_step)


def feed(sim: Simulation, events: Iterable[Event], until_step: int | None = None) -> Replayed:
    """Feed the inputs among ``events`` to ``sim`` (new, not stepped yet, with its observers)
    at their steps. The simulation steps on to ``until_step`` (default: the last event's step)
    after the last input.
    """
    result = Replayed(sim)
    last = 0
    for event in events:
        last = max(last, event.step)
        if not isinstance(event, INPUTS + SHOWN):
            continue
        while sim.steps < event.step:
            sim.step()
        if isinstance(event, SHOWN):
            sim.emit(event)  # shown again for the observers (a replay's overlay, the outcome)
        elif isinstance(event, CommandEvent):
            replies = sim.command(event.message, client=event.client)
            if not same_replies(replies, event.replies):
                result.differences.append(
                    f"step {event.step}: {event.message!r} answered {replies}, "
                    f"recorded {list(event.replies)}"
                )
        elif isinstance(event, KeysEvent):
            sim.set_manual_keys(event.keys)
        elif isinstance(event, PlaceEvent):
            sim.place_robot(*event.pose)
        else:
            sim.reset()
            last = 0
    end = last if until_step is None else until_step
    while sim.steps < end:
        sim.step()
    return result
