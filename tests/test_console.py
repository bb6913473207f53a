"""The interactive console (``simmer console``): its own help, and why a reply is NaN."""

from __future__ import annotations

from link_support import serving
from simmer.client import connect
from simmer.console import HELP, run_console
from simmer.world import Simulation
from simmer.world.events import CommandEvent, Event


def test_console_answers_help_itself() -> None:
    lines = iter(["help", "?", "u0", "quit"])
    shown: list[str] = []
    sim = Simulation.from_config()
    seen: list[Event] = []
    sim.add_observer(seen.append)
    with serving(sim) as (_, link), connect(port=link.stream.port) as client:
        run_console(client, read=lambda _: next(lines), echo=shown.append, history=False)
    assert shown[:3] == [HELP, HELP, HELP]
    commands = [e.message for e in seen if isinstance(e, CommandEvent)]
    assert commands == ["u0"]  # help never reached the simulator


def test_console_shows_why_a_reply_is_nan() -> None:
    lines = iter(["zz", "u1", "quit"])
    shown: list[str] = []
    with serving() as (_, link), connect(port=link.stream.port, timeout=10) as robot:
        run_console(robot, read=lambda _prompt: next(lines), echo=shown.append, history=False)
    text = "\n".join(shown)
    assert "why: " in text
    assert "no device 'zz' on the robot" in text
    assert text.count("why: ") == 1  # not after u1's reading
