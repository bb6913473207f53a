"""The HUD's command log: repeated polls take one line."""

from __future__ import annotations

import math

from simmer.ui import RecordingRenderer
from simmer.ui.hud import paint_hud
from simmer.view.commands import CommandLog, RepeatedCommand
from simmer.view.snapshot import Snapshot
from simmer.world import Simulation


def test_repeated_polls_take_one_hud_line() -> None:
    """``wait_idle()`` polls ``w0-0`` until the drive is done: one line with a count."""
    sim = Simulation.from_config()
    log = CommandLog()
    sim.add_observer(log)
    sim.command("u0")
    sim.command("w0-12")
    polls = 0
    while math.isnan(sim.command("w0-0")[0]):
        polls += 1
        sim.step(3)
    assert polls > 5
    entries = list(log.entries)
    assert [e.message for e in entries] == ["u0", "w0-12", "w0-0", "w0-0"]
    assert isinstance(entries[2], RepeatedCommand)
    assert entries[2].count == polls
    rec = RecordingRenderer()
    paint_hud(rec, Snapshot.of(sim, commands=entries))
    texts = [str(args[0]) for args in rec.of("text")]
    assert any(t.endswith(f"w0-0 -> NaN  x{polls}") for t in texts)
    assert any(" u0 -> " in t for t in texts)  # the student's own command is still shown
