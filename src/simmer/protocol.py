"""The command language, as pure functions: text in, commands out (BEHAVIOUR §6).

A message is one or more commands separated by commas (``u0,u1,w0-12``). A command is a
two-character device id, optionally followed by a separator (``-``, or ``:`` as SimMeR v1.2
writes it) and a decimal number (``w0--6`` moves back 6 in); a bare id means value 0.

Two ways to read a command:

* strict (the native format's default): anything else is a malformed command, answered with
  NaN and the reason logged, instead of SimMeR's silent 0;
* lenient (a run from an original ``config.py``, BEHAVIOUR §6.2): the originals' way, the third
  character is skipped whatever it is and a value ``float()`` cannot read counts as 0. The
  command then names the rules it used (``lenient``), so the simulation can warn once.
  Non-finite values and values beyond ±1e9 are still refused (the original would drive
  forever): a difference on purpose.

The second half is the byte level shared by every transport: decoding a received message
(non-text bytes become NaN replies, never a dead listener) and the two reply codecs, packed
little-endian float32/float64 (SimMeR v1.0/v1.1, the Arduino examples, the persistent
protocol's frames) and SimMeR v1.2's framed text (``[u0]`` -> ``[u0:15.45]``, BEHAVIOUR §6.1).
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

STOP_ID = "xx"
SEPARATOR = "-"
SEPARATORS = ("-", ":")
"""What strict parsing accepts after the device id: SimMeR's ``-`` and SimMeR v1.2's ``:``."""
MAX_ABS_VALUE = 1e9
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


@dataclass(frozen=True)
class Command:
    """One parsed command. ``error`` is set (and the reply will be NaN) if it is malformed."""

    text: str
    device: str = ""
    value: float = 0.0
    error: str | None = None
    lenient: tuple[str, ...] = ()
    """Lenient parsing only: the originals' rules this reading used (:data:`LENIENT_RULES`)."""


LENIENT_RULES = {
    "skip": "the third character is skipped whatever it is",
    "zero": "a value that is not a number is read as 0",
}
"""The originals' parsing rules that strict parsing does not follow (BEHAVIOUR §6.2)."""


def parse_command(text: str, *, lenient: bool = False) -> Command:
    """Parse one command such as ``w0-6``, ``u0`` or ``r0--90`` (see the module doc)."""
    stripped = text.strip()
    if not stripped:
        return Command(text, error="empty command")
    if len(stripped) < 2:
        return Command(text, error=f"{stripped!r} is too short: a device id has two characters")
    device = stripped[:2]
    if len(stripped) == 2:
        return Command(text, device, 0.0)
    if lenient:
        return _parse_lenient(text, stripped)
    if stripped[2] not in SEPARATORS:
        return Command(
            text,
            device,
            error=f"expected '{SEPARATOR}' after the device id {device!r}, "
            f"got {stripped[2]!r} (write e.g. '{device}-5')",
        )
    raw = stripped[3:]
    if not _NUMBER.fullmatch(raw):
        return Command(text, device, error=f"{raw!r} is not a decimal number")
    return _in_range(Command(text, device, float(raw)), raw)


def _parse_lenient(text: str, stripped: str) -> Command:
    """The originals' reading: skip character 3, ``float()`` the rest, 0 if that fails."""
    device, skipped, raw = stripped[:2], stripped[2], stripped[3:]
    rules: tuple[str, ...] = () if skipped in SEPARATORS else ("skip",)
    try:
        value = float(raw)
    except ValueError:
        value = 0.0
        rules += ("zero",)
    return _in_range(Command(text, device, value, lenient=rules), raw)


def _in_range(command: Command, raw: str) -> Command:
    """Refuse NaN, infinities and values beyond ±1e9 (no drive or sensor means them)."""
    if math.isfinite(command.value) and abs(command.value) <= MAX_ABS_VALUE:
        return command
    return Command(
        command.text,
        command.device,
        error=f"{raw!r} is out of range (at most ±{MAX_ABS_VALUE:g})",
    )


def parse_message(text: str, *, lenient: bool = False) -> list[Command]:
    """Split a message on commas and parse each command; an empty message is one bad command."""
    return [parse_command(part, lenient=lenient) for part in text.strip().split(",")]


def command_ids(text: str) -> list[str]:
    """The device id of each command of a message, as a reply names it (first two characters)."""
    return [part.strip()[:2] for part in text.strip().split(",")]


# --------------------------------------------------------------------------- bytes and framing

MAX_MESSAGE_BYTES = 64 * 1024
"""Longest message accepted, in bytes (without its line ending)."""

REPLY_FORMATS = {4: "<f", 8: "<d"}
"""``struct`` format of one reply value by width: float32 (SimMeR 1.1, Arduino) or float64."""

FRAME_HEADER = struct.Struct("<BH")
"""Persistent-protocol reply header: value width in bytes (4 or 8), then the value count."""


@dataclass(frozen=True)
class Decoded:
    """A message as received: its text, or (``text is None``) why it cannot be executed.

    ``count`` is how many NaN replies an undecodable message gets: one per comma-separated
    command, so a client still receives exactly one value per command it sent.
    """

    text: str | None
    count: int = 1
    error: str | None = None
    ids: tuple[str, ...] = ()
    """Framed text only: the ids of an undecodable message's commands, for its NaN reply."""


def decode_message(data: bytes, encoding: str = "utf-8") -> Decoded:
    """Decode the bytes of one message (line ending already removed, or not)."""
    if len(data) > MAX_MESSAGE_BYTES:
        return Decoded(None, 1, f"message of {len(data)} bytes is over {MAX_MESSAGE_BYTES}")
    count = data.count(b",") + 1
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as exc:
        return Decoded(None, count, f"not {encoding} text ({exc.reason} at byte {exc.start})")
    return Decoded(text.rstrip("\r\n"), count)


def pack_replies(values: Sequence[float], width: int = 4) -> bytes:
    """Pack reply values as little-endian floats of ``width`` bytes (4 or 8), no framing."""
    fmt = REPLY_FORMATS[width]
    return struct.pack(f"<{len(values)}{fmt[1]}", *values)


def unpack_replies(data: bytes, width: int = 4) -> list[float]:
    """Inverse of :func:`pack_replies`; ``len(data)`` must be a multiple of ``width``."""
    if len(data) % width:
        raise ValueError(f"{len(data)} bytes is not a whole number of {width}-byte values")
    fmt = REPLY_FORMATS[width]
    return list(struct.unpack(f"<{len(data) // width}{fmt[1]}", data))


def frame_replies(values: Sequence[float], width: int = 4) -> bytes:
    """Persistent protocol: header (width, count) followed by the packed values."""
    return FRAME_HEADER.pack(width, len(values)) + pack_replies(values, width)


def read_frame_header(header: bytes) -> tuple[int, int]:
    """Parse a persistent-protocol reply header; returns (width, count)."""
    width, count = FRAME_HEADER.unpack(header)
    if width not in REPLY_FORMATS:
        raise ValueError(f"bad reply header: value width {width} (expected 4 or 8)")
    return width, count


# --------------------------------------------------------------------------- reply codecs


class ReplyCodec(Protocol):
    """How a transport reads a message from bytes and writes its reply values as bytes."""

    def decode(self, data: bytes) -> Decoded:
        """The message in ``data``; ``count == 0`` with no text means: send nothing back."""
        ...

    def encode(self, decoded: Decoded, values: Sequence[float]) -> bytes:
        """The reply to ``decoded`` (``b""``: nothing to send)."""
        ...


@dataclass(frozen=True)
class PackedCodec:
    """SimMeR v1.0/v1.1 and the Arduino: one packed float of ``width`` bytes per command."""

    width: int = 4
    encoding: str = "utf-8"

    def decode(self, data: bytes) -> Decoded:
        """The text of the bytes (see :func:`decode_message`)."""
        return decode_message(data, self.encoding)

    def encode(self, decoded: Decoded, values: Sequence[float]) -> bytes:
        """The values packed, no framing."""
        return pack_replies(values, self.width)


def unwrap_frames(text: str, start: str = "[", end: str = "]") -> str | None:
    """The commands of every complete frame in ``text``, joined by commas (``[u0][u1]`` ->
    ``u0,u1``); text outside frames is ignored; None if there is no complete frame."""
    parts = []
    position = 0
    while (first := text.find(start, position)) >= 0:
        last = text.find(end, first + len(start))
        if last < 0:
            break
        parts.append(text[first + len(start) : last])
        position = last + len(end)
    return ",".join(parts) if parts else None


@dataclass(frozen=True)
class FramedCodec:
    """SimMeR v1.2's framed text (BEHAVIOUR §6.1): ``[u0,w0:6]`` -> ``[u0:15.45,w0:True]``.

    ``categories`` maps each device id to ``"motor"``, ``"drive"`` or ``"sensor"``: a drive
    answers ``True`` (accepted) or ``False`` (refused, NaN), ``xx`` answers ``DRIVE STOP``, an
    unknown id ``Not Found``, anything else its reading rounded to ``round_digits`` decimals and
    written as Python writes a float (``15.45``, ``433.0``, ``nan``).
    """

    categories: Mapping[str, str]
    start: str = "["
    end: str = "]"
    round_digits: int = 3
    encoding: str = "ascii"

    def decode(self, data: bytes) -> Decoded:
        """The commands of the frames in ``data``; no complete frame: nothing is sent back."""
        if len(data) > MAX_MESSAGE_BYTES:
            return Decoded(None, 0, f"message of {len(data)} bytes is over {MAX_MESSAGE_BYTES}")
        plain = decode_message(data, self.encoding)
        text = data.decode(self.encoding, errors="replace") if plain.text is None else plain.text
        commands = unwrap_frames(text, self.start, self.end)
        if commands is None:
            shown = text if len(text) <= 40 else text[:37] + "..."
            return Decoded(
                None,
                0,
                f"no complete frame {self.start}...{self.end} in {shown!r}; nothing is sent "
                f"back (SimMeR v1.2 frames every message, e.g. {self.start}u0{self.end})",
            )
        if plain.text is None:
            ids = tuple(command_ids(commands))
            return Decoded(None, len(ids), plain.error, ids)
        return Decoded(commands)

    def encode(self, decoded: Decoded, values: Sequence[float]) -> bytes:
        """One frame with an ``id:value`` entry per command, in order."""
        if not values:
            return b""
        ids = command_ids(decoded.text) if decoded.text is not None else list(decoded.ids)
        entries = ",".join(self.entry(i, v) for i, v in zip(ids, values, strict=False))
        return f"{self.start}{entries}{self.end}".encode(self.encoding, errors="replace")

    def entry(self, device_id: str, value: float) -> str:
        """One reply entry, ``id:value``."""
        if device_id == STOP_ID:
            return f"{STOP_ID}:DRIVE STOP"
        category = self.categories.get(device_id)
        if category is None:
            return f"{device_id}:Not Found"
        if category == "drive":
            return f"{device_id}:{not math.isnan(value)}"
        return f"{device_id}:{round(float(value), self.round_digits)!r}"


def read_framed_reply(text: str, start: str = "[", end: str = "]") -> list[tuple[str, str]]:
    """Split a SimMeR v1.2 reply (``[u0:15.45,w0:True]``) into (id, value text) pairs."""
    inner = unwrap_frames(text, start, end)
    if inner is None:
        raise ValueError(f"{text!r} is not a framed reply ({start}id:value,...{end})")
    pairs = []
    for entry in inner.split(","):
        device_id, _, value = entry.partition(":")
        pairs.append((device_id, value))
    return pairs


def framed_value(value: str) -> float:
    """A v1.2 reply entry's value as the packed protocol's number: ``True`` and ``DRIVE STOP``
    -> +inf, ``False`` and ``Not Found`` -> NaN, a number -> itself."""
    if value in ("True", "DRIVE STOP"):
        return math.inf
    if value in ("False", "Not Found"):
        return math.nan
    try:
        return float(value)
    except ValueError:
        return math.nan
