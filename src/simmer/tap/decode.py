"""What the bytes a tap forwards say: a program's messages and the robot's replies, paired.

The tap forwards bytes unchanged and reads along: :class:`TapDecoder` is fed each chunk as it
passes (``sent`` from the program, ``received`` from the robot) and gives back each exchange
(:class:`Exchange`: the message, its reply values, when each was seen) once its reply is
whole. It decodes the protocol the configuration names (``protocol``, ``reply_bytes``,
``frame_start``, ``frame_end``), as the robot's Arduino sketch reads it:

- packed (SimMeR v1.0/v1.1): a message ends at ``\\n`` (or after :data:`SILENCE` of quiet,
  which :meth:`TapDecoder.quiet` ends), and its reply is ``reply_bytes`` bytes per command;
- framed (SimMeR v1.2): a message is the text of a frame (``[u0,w0:6]``), text outside frames
  is skipped, and a reply frame's entries answer the messages in order, a command each.

Replies answer messages first in, first out, as the robot answers them. Bytes that answer
nothing (a reply with no message waiting) are counted in :attr:`TapDecoder.stray`, and a
message still waiting when the tap ends is an exchange with no reply (the run folder keeps it
with NaN: the robot never answered).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

from simmer.protocol import command_ids, framed_value, unpack_replies

SILENCE = 0.05
"""Seconds of quiet that end a packed message without a newline (the Arduino sketch's rule)."""
MAX_PENDING_BYTES = 65_536
"""Bytes of a message or a reply a tap holds while it waits for the rest: a program (or a
robot) sending more without ending it is not speaking the protocol, and what it sent so far is
dropped from the decoding (still forwarded) and counted in :attr:`TapDecoder.stray`."""


@dataclass
class Exchange:
    """One message and its reply: ``sent`` and ``replied`` are wall-clock seconds (the
    tap's clock), ``replies`` one value per command (NaN for one the robot never answered)."""

    message: str
    commands: int
    sent: float
    replies: list[float] = field(default_factory=list)
    replied: float | None = None
    reply_text: str = ""


class TapDecoder:
    """Pairs a program's messages with the robot's replies (see the module doc)."""

    def __init__(
        self,
        protocol: str = "packed",
        width: int = 4,
        frame: tuple[str, str] = ("[", "]"),
        encoding: str = "ascii",
    ) -> None:
        self.protocol = protocol
        self.width = width
        self.start, self.end = frame
        self.encoding = encoding
        self._out = bytearray()
        """Bytes from the program not yet a whole message."""
        self._in = bytearray()
        """Bytes from the robot not yet a whole reply."""
        self._last_sent = 0.0
        self.waiting: deque[Exchange] = deque()
        """Messages sent whose reply is not whole yet, oldest first."""
        self.stray = 0
        """Bytes that were neither part of a message nor of a reply to one."""

    # -- the program's side

    def sent(self, data: bytes, now: float) -> list[Exchange]:
        """Bytes the program wrote (forwarded already); exchanges completed by them (none:
        only the robot's bytes complete one; the list is for symmetry with :meth:`received`)."""
        self._out += data
        self._last_sent = now
        if self.protocol == "framed":
            self._frames(now)
        else:
            while (end := self._out.find(b"\n")) >= 0:
                line = bytes(self._out[:end]).rstrip(b"\r")
                del self._out[: end + 1]
                self._message(line, now)
        if len(self._out) > MAX_PENDING_BYTES:
            self.stray += len(self._out)
            self._out.clear()
        return []

    def _frames(self, now: float) -> None:
        start, end = self.start.encode(), self.end.encode()
        while True:
            begin = self._out.find(start)
            if begin < 0:
                self.stray += len(self._out)
                self._out.clear()
                return
            close = self._out.find(end, begin + 1)
            if close < 0:
                self.stray += begin
                del self._out[:begin]
                return
            self.stray += begin
            self._message(bytes(self._out[begin + 1 : close]), now)
            del self._out[: close + 1]

    def _message(self, data: bytes, now: float) -> None:
        text = data.decode(self.encoding, errors="replace").strip()
        if not text:
            return
        count = len(command_ids(text)) or 1
        self.waiting.append(Exchange(text, count, now))

    def quiet(self, now: float) -> None:
        """End a packed message after :data:`SILENCE` of quiet (the Arduino's rule)."""
        if self.protocol == "packed" and self._out and now - self._last_sent >= SILENCE:
            self._end_pending()

    def _end_pending(self) -> None:
        data = bytes(self._out).rstrip(b"\r")
        self._out.clear()
        self._message(data, self._last_sent)

    # -- the robot's side

    def received(self, data: bytes, now: float) -> list[Exchange]:
        """Bytes the robot wrote (forwarded already); the exchanges they complete, in order."""
        self._in += data
        done: list[Exchange] = []
        if self.protocol == "framed":
            self._reply_frames(now, done)
        else:
            if self._out and not self.waiting:  # an answer to nothing else: the robot took
                # what the program sent so far as a message ended by silence
                self._end_pending()
            while self.waiting:
                first = self.waiting[0]
                size = first.commands * self.width
                if len(self._in) < size:
                    break
                chunk = bytes(self._in[:size])
                del self._in[:size]
                first.replies = unpack_replies(chunk, self.width)
                first.replied = now
                first.reply_text = chunk.hex()
                done.append(self.waiting.popleft())
            if not self.waiting and self._in:
                self.stray += len(self._in)
                self._in.clear()
        if len(self._in) > MAX_PENDING_BYTES:
            self.stray += len(self._in)
            self._in.clear()
        return done

    def _reply_frames(self, now: float, done: list[Exchange]) -> None:
        start, end = self.start.encode(), self.end.encode()
        while (close := self._in.find(end)) >= 0:
            begin = self._in.rfind(start, 0, close)
            frame = bytes(self._in[begin + 1 : close]) if begin >= 0 else b""
            del self._in[: close + 1]
            text = frame.decode(self.encoding, errors="replace")
            for entry in text.split(",") if text else []:
                self._answer(entry, now, done)

    def _answer(self, entry: str, now: float, done: list[Exchange]) -> None:
        """One ``id:value`` entry of a reply frame: the next command waiting for one."""
        if not self.waiting:
            self.stray += len(entry)
            return
        first = self.waiting[0]
        value = entry.partition(":")[2]
        first.replies.append(framed_value(value))
        first.reply_text += ("," if first.reply_text else "") + entry
        if len(first.replies) >= first.commands:
            first.replied = now
            done.append(self.waiting.popleft())

    def unanswered(self) -> list[Exchange]:
        """The messages still waiting (the tap is ending): each with NaN for every command
        the robot never answered."""
        left = list(self.waiting)
        self.waiting.clear()
        for exchange in left:
            exchange.replies += [math.nan] * (exchange.commands - len(exchange.replies))
        return left
