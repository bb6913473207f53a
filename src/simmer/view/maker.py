"""Snapshots of a simulation with what the HUD shows besides it, and the pause and speed
controls a snapshot reports.

Both the window's :class:`~simmer.ui.bridge.Bridge` and the video
(:class:`~simmer.ui.video.VideoRecorder`) build their snapshots here, in the thread that owns
the simulation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from simmer.geometry import FloatArray
from simmer.localize.belief import BeliefBoard
from simmer.view.commands import CommandLog
from simmer.view.snapshot import RobotLayout, Snapshot
from simmer.view.trail import Trail
from simmer.world import Simulation
from simmer.world.events import Observer
from simmer.world.outcome import Outcome


class Controls(Protocol):
    """What a snapshot shows of the loop that steps the simulation, and what the bridge asks of
    it (the Runner has these)."""

    paused: bool
    speed: float | None

    @property
    def clients(self) -> Sequence[str] | None:
        """Connected clients (None: nothing is served)."""
        ...

    def step_once(self) -> None:
        """Advance one step."""
        ...


@dataclass
class LocalControls:
    """Pause and speed state when no runner drives the simulation (tests, off-screen drawing)."""

    sim: Simulation
    paused: bool = False
    speed: float | None = 1.0
    clients: Sequence[str] | None = None

    def step_once(self) -> None:
        """Advance one step."""
        self.sim.step()


class SnapshotMaker:
    """Builds :class:`Snapshot` values of one simulation, with what the HUD shows besides it:
    the run's outcome, the last commands, the trail and the program's belief (observers it
    adds to ``sim`` unless ``sim`` has them already). The window's
    :class:`~simmer.ui.bridge.Bridge` and the video (:class:`~simmer.ui.video.VideoRecorder`)
    each have one.

    Use it only in the thread that owns ``sim``.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        outcome = next((o for o in sim.observers if isinstance(o, Outcome)), None)
        self._attached: list[Observer] = []
        """The observers this maker added (and removes on :meth:`close`)."""
        if outcome is None:
            outcome = Outcome(sim)
            self._attached.append(outcome)
        self.outcome = outcome
        """The run's outcome the HUD shows: the one already following ``sim`` (a served run
        reports the same figures at its end), else this maker's own."""
        trail = next((o for o in sim.observers if isinstance(o, Trail)), None)
        if trail is None:
            trail = Trail(sim.robot.pose)
            self._attached.append(trail)
        self.trail = trail
        """The path driven so far: shared like :attr:`outcome` (a video started from the window
        shows the window's trail)."""
        board = next((o for o in sim.observers if isinstance(o, BeliefBoard)), None)
        if board is None:
            board = BeliefBoard()
            self._attached.append(board)
        self.beliefs = board
        """The belief the program showed last: shared too."""
        commands = next((o for o in sim.observers if isinstance(o, CommandLog)), None)
        if commands is None:
            commands = CommandLog()
            self._attached.append(commands)
        self.commands = commands
        """The last commands: shared too (a frame drawn after the run shows its last ones)."""
        for observer in self._attached:
            sim.add_observer(observer)
        self._robot = sim.robot
        self._layout = RobotLayout.of(sim.robot)

    def snapshot(
        self,
        ctl: Controls,
        ghost: FloatArray | None = None,
        recording: str | None = None,
        notice: str | None = None,
    ) -> Snapshot:
        """The simulation now, with ``ctl``'s pause, speed and clients."""
        sim = self.sim
        if sim.robot is not self._robot:  # after a reset
            self._robot = sim.robot
            self._layout = RobotLayout.of(sim.robot)
        return Snapshot.of(
            sim,
            self._layout,
            paused=ctl.paused,
            speed=ctl.speed,
            outcome=self.outcome.report(),
            commands=self.commands.entries,
            clients=ctl.clients,
            ghost=ghost,
            recording=recording,
            notice=notice,
            trail=self.trail.view(),
            belief=self.beliefs.belief,
        )

    def close(self) -> None:
        """Stop observing the simulation (once its thread has stopped)."""
        for observer in self._attached:
            self.sim.remove_observer(observer)
