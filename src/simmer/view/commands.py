"""The last few commands and their replies, as the HUD shows them: a pygame-free observer of
the simulation (a sweep keeps one for a failure's last frame without drawing anything)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from simmer.world.events import CommandEvent, Event
from simmer.world.replay import same_replies


@dataclass(frozen=True)
class RepeatedCommand(CommandEvent):
    """A message answered the same way ``count`` times in a row; ``time`` is the last one's."""

    count: int = 1


class CommandLog:
    """The last few messages and their replies, collected from the simulation's events.

    A message answered as the one before it was (``wait_idle()`` polling ``w0-0`` until the
    drive is done) extends that entry's count instead of taking a line, so the student's own
    commands stay on screen.
    """

    def __init__(self, size: int = 5) -> None:
        self.entries: deque[CommandEvent] = deque(maxlen=size)

    def __call__(self, event: Event) -> None:
        """Observe one simulation event."""
        if not isinstance(event, CommandEvent):
            return
        last = self.entries[-1] if self.entries else None
        if (
            last is None
            or last.message != event.message
            or not same_replies(last.replies, event.replies)
        ):
            self.entries.append(event)
            return
        count = last.count if isinstance(last, RepeatedCommand) else 1
        self.entries[-1] = RepeatedCommand(
            time=event.time,
            message=event.message,
            replies=event.replies,
            step=event.step,
            client=event.client,
            count=count + 1,
        )
