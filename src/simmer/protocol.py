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
  forever), and so is a value with any character outside ASCII (``float()`` reads ``٥`` and
  ``６`` as digits): differences on purpose.

Only the ASCII digits 0-9 are digits, in both readings. Text a client sent is written into the
log through :func:`printable`, so it cannot move the cursor or reorder the line.

The second half is the byte level shared by every transport: decoding a received message
(non-text bytes become NaN replies, never a dead listener) and the two reply codecs, packed
little-endian float32/float64 (SimMeR v1.0/v1.1, the Arduino examples, the persistent
protocol's frames) and SimMeR v1.2's framed text (``[u0]`` -> ``[u0:15.45]``, BEHAVIOUR §6.1).
"""

from __future__ import annotations

import functools
import math
import re
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import ClassVar, Protocol

STOP_ID = "xx"
SEPARATOR = "-"
SEPARATORS = ("-", ":")
"""What strict parsing accepts after the device id: SimMeR's ``-`` and SimMeR v1.2's ``:``."""
MAX_ABS_VALUE = 1e9
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
"""A decimal number in ASCII digits (``\\d`` would also match ``٥`` and ``６``)."""


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
        only = "" if raw.isascii() else " (only the ASCII digits 0-9 are read)"
        return Command(text, device, error=f"{raw!r} is not a decimal number{only}")
    return _in_range(Command(text, device, float(raw)), raw)


def _parse_lenient(text: str, stripped: str) -> Command:
    """The originals' reading: skip character 3, ``float()`` the rest, 0 if that fails.

    Unlike the originals, a value with a character outside ASCII is refused (NaN, with the
    reason): ``float()`` reads other scripts' digits (``٥``, ``６``) and spaces, which a
    student never meant as a number. A difference on purpose.
    """
    device, skipped, raw = stripped[:2], stripped[2], stripped[3:]
    if not raw.isascii():
        return Command(
            text,
            device,
            error=f"{raw!r} has characters outside ASCII (only the digits 0-9 are read)",
        )
    rules: tuple[str, ...] = () if skipped in SEPARATORS else ("skip",)
    try:
        value = float(raw)
    except ValueError:
        value = 0.0
        rules += ("zero",)
    return _in_range(Command(text, device, value, lenient=rules), raw)


def decimal_number(raw: str) -> float | None:
    """``raw`` read as a command's value is (strict parsing): a decimal number in ASCII digits
    within ±:data:`MAX_ABS_VALUE`; None otherwise (``1_0``, ``１２``, ``٥``, ``nan``, ``1e400``,
    which ``float()`` reads)."""
    if not _NUMBER.fullmatch(raw):
        return None
    value = float(raw)
    return value if abs(value) <= MAX_ABS_VALUE else None


def _in_range(command: Command, raw: str) -> Command:
    """Refuse NaN, infinities and values beyond ±1e9 (no drive or sensor means them)."""
    if math.isfinite(command.value) and abs(command.value) <= MAX_ABS_VALUE:
        return command
    return Command(
        command.text,
        command.device,
        error=f"{raw!r} is out of range (at most ±{MAX_ABS_VALUE:g})",
    )


def printable(text: str) -> str:
    """``text`` safe to quote in a log line: each character that is not printable written as
    its Python escape (ESC as ``\\x1b``, the right-to-left override as ``\\u202e``).

    Clients choose what they send; unescaped, a terminal escape could recolour or clear the
    terminal and a bidirectional control could reorder the line. Non-printable means what
    :meth:`str.isprintable` says: control characters, format characters (every bidirectional
    control) and separators other than the space. Printable text comes back unchanged, so text
    already quoted with ``repr`` is not escaped twice.
    """
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in text)


def parse_message(text: str, *, lenient: bool = False) -> list[Command]:
    """Split a message on commas and parse each command; an empty message is one bad command."""
    return list(parse_commands(text, lenient=lenient))


CACHED_MESSAGE_CHARS = 256
"""Messages up to this long are parsed once and remembered (:func:`parse_commands`)."""
CACHED_LONG_MESSAGES = 8
"""Longer messages within the message limits remembered (:func:`parse_commands`): at most
this many, about 0.3 MB each at the limits (``MAX_MESSAGE_BYTES``, ``MAX_COMMANDS``)."""


def parse_commands(text: str, *, lenient: bool = False) -> tuple[Command, ...]:
    """:func:`parse_message` as a tuple, remembered for the last 1,024 short messages and the
    last :data:`CACHED_LONG_MESSAGES` long ones: a program sends the same few messages
    (``u0,u1,u2,u3``; a LiDAR's whole-scan read, some 3 KB) thousands of times, and a
    :class:`Command` is immutable, so the loop need not parse (or build) them again. A
    message over a limit (:func:`over_limit`) is parsed each time, never kept."""
    if len(text) <= CACHED_MESSAGE_CHARS:
        return _parse_cached(text, lenient)
    if len(text) <= MAX_MESSAGE_BYTES and text.count(",") < MAX_COMMANDS:
        return _parse_long_cached(text, lenient)
    return _parse_uncached(text, lenient)


def _parse_uncached(text: str, lenient: bool) -> tuple[Command, ...]:
    return tuple(parse_command(part, lenient=lenient) for part in text.strip().split(","))


_parse_cached = functools.lru_cache(maxsize=1024)(_parse_uncached)
_parse_long_cached = functools.lru_cache(maxsize=CACHED_LONG_MESSAGES)(_parse_uncached)


def command_ids(text: str) -> list[str]:
    """The device id of each command of a message, as a reply names it (first two characters)."""
    return [part.strip()[:2] for part in text.strip().split(",")]


# --------------------------------------------------------------------------- bytes and framing

MAX_MESSAGE_BYTES = 64 * 1024
"""Longest message accepted, in bytes (without its line ending)."""

MAX_COMMANDS = 1000
"""Most commands in one message. A message over it answers one NaN and runs nothing: 1,000
commands cost the loop about 15 ms (one frame at 60 steps/s, ultrasonic reads being the
dearest), far more than a robot program sends at once (one per device, a dozen devices), and
their reply frame stays a few kilobytes. The persistent protocol's uint16 count could say
65,535, but such a message would hold every other client up for a second."""

REPLY_FORMATS = {4: "<f", 8: "<d"}
"""``struct`` format of one reply value by width: float32 (SimMeR 1.1, Arduino) or float64."""

FRAME_HEADER = struct.Struct("<BH")
"""Persistent-protocol reply header: value width in bytes (4 or 8), then the value count."""
MAX_FRAME_COUNT = 0xFFFF
"""The most a frame header's count can say."""

EXPLAIN = b"?"
"""Persistent protocol: a line asking why the last message's replies were NaN; the answer is
a text frame (header width :data:`TEXT_WIDTH`, count = bytes of UTF-8 text)."""
TEXT_WIDTH = 0
MAX_TEXT_BYTES = 4096
"""Longest text frame: a few dozen reasons."""


# A message as received is one of four kinds (:data:`Decoded`), each a frozen dataclass: the
# loop and the transports match on the kind once, instead of on flag fields. Every kind has
# ``text`` (None: undecodable), ``count`` (how many replies it gets: one per comma-separated
# command, so a client receives exactly one value per command it sent), ``size`` (bytes of the
# transport's stream it used, its line ending too: what the clock counts as taken once it is
# answered, see :func:`parse_clock`) and ``over_limit``.


@dataclass(frozen=True)
class CommandText:
    """Robot commands: ``text``, and its commands parsed once where it was decoded (empty:
    not parsed yet)."""

    text: str
    count: int = 1
    commands: tuple[Command, ...] = ()
    size: int = 0
    dropped: str = ""
    """SimMeR v1.2 framed text only: the frames after the first, which are not answered (as
    the original answered one frame per message), shortened for the log; empty if none."""
    over_limit: ClassVar[bool] = False


@dataclass(frozen=True)
class ClockText:
    """A clock message (persistent protocol, ``!...``; see :func:`parse_clock`): one reply."""

    text: str
    size: int = 0
    count: ClassVar[int] = 1
    over_limit: ClassVar[bool] = False


@dataclass(frozen=True)
class LocalizationText:
    """A localization message (persistent protocol, ``%...``; see :func:`decode_meta`)."""

    text: str
    size: int = 0
    count: ClassVar[int] = 1
    over_limit: ClassVar[bool] = False


@dataclass(frozen=True)
class Refused:
    """A message that cannot be executed, and why: ``count`` NaN replies (a message over a
    limit gets one; a framed one with no frame, none: nothing is sent back)."""

    error: str
    count: int = 1
    ids: tuple[str, ...] = ()
    """Framed text only: the ids of an undecodable message's commands, for its NaN reply."""
    over_limit: bool = False
    """Over :data:`MAX_MESSAGE_BYTES` or :data:`MAX_COMMANDS`: nothing in it runs, and the
    persistent protocol closes the connection after the reply (its framing cannot be trusted)."""
    clock: bool = False
    """It came as a clock message: its NaN goes out as a time does (float64)."""
    size: int = 0
    text: ClassVar[None] = None


Decoded = CommandText | ClockText | LocalizationText | Refused
"""A message as received: one of the four kinds (see above)."""


def over_limit(size: int, commands: int, *, framed: bool = False) -> Refused | None:
    """What a message of ``size`` bytes and ``commands`` commands decodes to if it breaks a
    limit (one NaN; ``framed``: nothing, as for a v1.2 message with no frame), else None."""
    count = 0 if framed else 1
    if size > MAX_MESSAGE_BYTES:
        return Refused(
            f"message of {size} bytes is over {MAX_MESSAGE_BYTES}",
            count,
            over_limit=True,
        )
    if commands > MAX_COMMANDS:
        return Refused(
            f"message of {commands} commands is over the limit of {MAX_COMMANDS}; send fewer "
            "at a time",
            count,
            over_limit=True,
        )
    return None


def _not_text(exc: UnicodeDecodeError, encoding: str) -> str:
    """Why bytes are not a message, for the log and the NaN's reason."""
    return f"not {encoding} text ({exc.reason} at byte {exc.start})"


def decode_message(
    data: bytes,
    encoding: str = "utf-8",
    *,
    size: int = 0,
    clock: bool = False,
    lenient: bool = False,
) -> Decoded:
    """Decode the bytes of one message (line ending already removed, or not) and parse its
    commands (``lenient``: the originals' way, :func:`parse_command`); the limits are checked
    before anything else is done with it. ``size`` goes into the result; ``clock``: it is a
    clock message (:class:`ClockText`, not parsed here)."""
    count = data.count(b",") + 1
    if (refused := over_limit(len(data), count)) is not None:
        return replace(refused, size=size)
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as exc:
        return Refused(_not_text(exc, encoding), count, size=size, clock=clock)
    text = text.rstrip("\r\n")
    if clock:
        return ClockText(text, size)
    return CommandText(text, count, parse_commands(text, lenient=lenient), size)


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
    """Persistent protocol: header (width, count) followed by the packed values; ValueError
    for more values than the header's count can say."""
    if len(values) > MAX_FRAME_COUNT:
        raise ValueError(f"{len(values)} values do not fit a frame (at most {MAX_FRAME_COUNT})")
    count = len(values)
    return struct.pack(f"<BH{count}{REPLY_FORMATS[width][1]}", width, count, *values)


def frame_text(text: str) -> bytes:
    """Persistent protocol: the text frame answering :data:`EXPLAIN` (width 0, then the
    number of bytes, then UTF-8 text cut to at most :data:`MAX_TEXT_BYTES`)."""
    data = text.encode("utf-8")[:MAX_TEXT_BYTES].decode("utf-8", errors="ignore").encode()
    return FRAME_HEADER.pack(TEXT_WIDTH, len(data)) + data


def read_frame_header(header: bytes) -> tuple[int, int]:
    """Parse a persistent-protocol reply header; returns (width, count)."""
    width, count = FRAME_HEADER.unpack(header)
    if width not in REPLY_FORMATS:
        raise ValueError(f"bad reply header: value width {width} (expected 4 or 8)")
    return width, count


# --------------------------------------------------------------------------- reply codecs


Replies = tuple[Decoded, Sequence[float]]
"""One answered message: what was asked and its reply values."""


class ReplyCodec(Protocol):
    """How a transport reads a message from bytes and writes its reply values as bytes.

    ``keeps`` is what the original's two-port transmit buffer held while nobody collected
    it (BEHAVIOUR §6.4): ``"first"`` (v1.0/v1.1: the first waiting reply; later ones were
    dropped) or ``"all"`` (v1.2: every reply, sent together in one frame)."""

    @property
    def keeps(self) -> str:
        """``"first"`` or ``"all"`` (see the class doc)."""
        ...

    def decode(self, data: bytes) -> Decoded:
        """The message in ``data``; ``count == 0`` with no text means: send nothing back."""
        ...

    def encode(self, decoded: Decoded, values: Sequence[float]) -> bytes:
        """The reply to ``decoded`` (``b""``: nothing to send)."""
        ...

    def encode_many(self, answered: Sequence[Replies]) -> bytes:
        """The replies to several messages as one packet (``b""``: nothing to send)."""
        ...

    def describe(self) -> str:
        """What the replies look like, for the start-up lines (``as packed 4-byte floats``)."""
        ...


@dataclass(frozen=True)
class PackedCodec:
    """SimMeR v1.0/v1.1 and the Arduino: one packed float of ``width`` bytes per command."""

    width: int = 4
    encoding: str = "utf-8"
    lenient: bool = False
    """Parse commands the original SimMeR's way (a run of an original ``config.py``)."""
    keeps: ClassVar[str] = "first"

    def decode(self, data: bytes) -> Decoded:
        """The text of the bytes and its commands (see :func:`decode_message`)."""
        return decode_message(data, self.encoding, lenient=self.lenient)

    def encode(self, decoded: Decoded, values: Sequence[float]) -> bytes:
        """The values packed, no framing."""
        return pack_replies(values, self.width)

    def encode_many(self, answered: Sequence[Replies]) -> bytes:
        """Every message's values packed, one after another."""
        return b"".join(self.encode(decoded, values) for decoded, values in answered)

    def describe(self) -> str:
        """``as packed 4-byte floats`` (or 8-byte doubles)."""
        return f"as packed {'8-byte doubles' if self.width == 8 else '4-byte floats'}"


def unwrap_frames(text: str, start: str = "[", end: str = "]") -> str | None:
    """The entries of every complete frame in ``text``, joined by commas (``[u0:1][u1:2]`` ->
    ``u0:1,u1:2``), as the stock v1.2 client reads a reply; text outside frames is ignored;
    None if there is no complete frame. (A request is its first frame: :func:`first_frame`.)"""
    parts = []
    position = 0
    while (first := text.find(start, position)) >= 0:
        last = text.find(end, first + len(start))
        if last < 0:
            break
        parts.append(text[first + len(start) : last])
        position = last + len(end)
    return ",".join(parts) if parts else None


MAX_SHOWN = 40
"""Characters of a framed message's text quoted in a log line (longer text is cut, ``...``)."""


def _shown(text: str) -> str:
    """``text`` cut to :data:`MAX_SHOWN` characters for a log line."""
    return text if len(text) <= MAX_SHOWN else text[: MAX_SHOWN - 3] + "..."


def first_frame(text: str, start: str = "[", end: str = "]") -> tuple[str, str] | None:
    """The commands of the first complete frame in ``text`` and the text after it, as SimMeR
    v1.2 reads a request (``[u0][u1]`` -> ``("u0", "[u1]")``, BEHAVIOUR §6.1); None if there
    is no complete frame."""
    first = text.find(start)
    if first < 0:
        return None
    last = text.find(end, first + len(start))
    if last < 0:
        return None
    return text[first + len(start) : last], text[last + len(end) :]


@dataclass(frozen=True)
class FramedCodec:
    """SimMeR v1.2's framed text (BEHAVIOUR §6.1): ``[u0,w0:6]`` -> ``[u0:15.45,w0:True]``.
    A message is its first frame: later ones are not answered (:attr:`CommandText.dropped`).

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
    lenient: bool = False
    """Parse commands the original SimMeR's way (a run of an original ``config.py``)."""
    keeps: ClassVar[str] = "all"

    def decode(self, data: bytes) -> Decoded:
        """The commands of the first frame in ``data`` (later frames: ``dropped``); no
        complete frame, or a message over a limit: nothing is sent back."""
        if (refused := over_limit(len(data), 0, framed=True)) is not None:
            return refused
        error = None
        try:
            text = data.decode(self.encoding)
        except UnicodeDecodeError as exc:
            error = _not_text(exc, self.encoding)
            text = data.decode(self.encoding, errors="replace")
        framed = first_frame(text, self.start, self.end)
        if framed is None:
            return Refused(
                f"no complete frame {self.start}...{self.end} in {_shown(text)!r}; nothing is "
                f"sent back (SimMeR v1.2 frames every message, e.g. {self.start}u0{self.end})",
                0,
            )
        commands, rest = framed
        later = rest.find(self.start)
        dropped = _shown(rest[later:]) if later >= 0 else ""
        count = commands.count(",") + 1
        if (refused := over_limit(0, count, framed=True)) is not None:
            return refused
        if error is not None:
            ids = tuple(command_ids(commands))
            return Refused(error, len(ids), ids)
        parsed = parse_commands(commands, lenient=self.lenient)
        return CommandText(commands, count, parsed, dropped=dropped)

    def encode(self, decoded: Decoded, values: Sequence[float]) -> bytes:
        """One frame with an ``id:value`` entry per command, in order."""
        return self.encode_many([(decoded, values)])

    def encode_many(self, answered: Sequence[Replies]) -> bytes:
        """One frame with the entries of every message, in order, as v1.2's ``make_tx_packet``
        sends its whole transmit buffer (``[w0:True,w0:True,g0:12.3]``); nothing if none."""
        entries = []
        for decoded, values in answered:
            ids = list(decoded.ids) if isinstance(decoded, Refused) else command_ids(decoded.text)
            entries += [self.entry(i, v) for i, v in zip(ids, values, strict=False)]
        if not entries:
            return b""
        text = f"{self.start}{','.join(entries)}{self.end}"
        return text.encode(self.encoding, errors="replace")

    def describe(self) -> str:
        """``in SimMeR v1.2 framed text ([u0] -> [u0:15.45], 3 decimals)``."""
        start, end = self.start, self.end
        return (
            f"in SimMeR v1.2 framed text ({start}u0{end} -> {start}u0:15.45{end}, "
            f"{self.round_digits} decimals)"
        )

    def entry(self, device_id: str, value: float) -> str:
        """One reply entry, ``id:value``."""
        if device_id == STOP_ID:
            return f"{STOP_ID}:DRIVE STOP"
        category = self.categories.get(device_id)
        if category is None:
            return f"{device_id}:Not Found"
        if category == "drive":
            return f"{device_id}:{not math.isnan(value) and value != 0.0}"  # a gripper: 0.0
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


# --------------------------------------------------------------------------- clock messages

CLOCK_PREFIX = b"!"
"""A persistent-protocol line starting with this is a clock message, not robot commands."""


@dataclass(frozen=True)
class ClockMessage:
    """``!sleep S`` (advance S seconds), ``!idle`` (until no drive moves), ``!time`` (the
    clock), ``!peek`` (the clock, never advancing it nor counted as a read, not recorded: a
    library's read) or ``!sync`` (nothing but the ``after`` condition).

    ``after`` (written `` @N`` at the end) is how many bytes the program has written towards
    the simulator on its other connections so far: the simulator acts on the clock message
    only once it has taken and answered that many, so a message the program sent before it
    slept is acted on before the sleep, whichever connection arrives first. None: no condition.
    ``counts`` (a last word ``+``): the answer has two more values, the bytes the simulator has
    sent to its clients so far and the two-port replies waiting to be collected, so that the
    lockstep shim can tell whether a reply is still on its way to the program.
    """

    kind: str
    seconds: float = 0.0
    after: int | None = None
    counts: bool = False


CLOCK_KINDS = ("time", "idle", "sync", "peek")
"""Clock messages without an argument (``!sleep`` takes the seconds)."""


def parse_clock(text: str) -> ClockMessage:
    """Parse a clock message; raises ``ValueError`` saying what is wrong."""
    words = text.strip().lstrip("!").split()
    counts = len(words) > 1 and words[-1] == "+"
    if counts:
        words.pop()
    after = None
    if len(words) > 1 and words[-1].startswith("@"):
        count = words.pop()[1:]
        if count.isascii() and count.isdigit() and len(count) <= 18:
            after = int(count)
        else:
            words = []  # refused below
    if len(words) == 1 and words[0] in CLOCK_KINDS:
        return ClockMessage(words[0], after=after, counts=counts)
    if len(words) == 2 and words[0] == "sleep" and _NUMBER.fullmatch(words[1]):
        seconds = float(words[1])
        if 0 <= seconds <= MAX_ABS_VALUE:
            return ClockMessage("sleep", seconds, after, counts)
        raise ValueError(
            f"{printable(text)!r}: a sleep of {words[1]} s is refused; it must be 0 to "
            f"{MAX_ABS_VALUE:g} s of simulated time (MAX_ABS_VALUE, as a command's value)"
        )
    raise ValueError(
        f"{printable(text)!r} is not a clock message: '!sleep SECONDS', '!idle', '!time', "
        "'!peek' or '!sync', each optionally followed by ' @BYTES' and then ' +'"
    )


# --------------------------------------------------------------------------- localization messages

META_PREFIX = b"%"
"""A persistent-protocol line starting with this is a localization message (``%maze``,
``%show JSON``, ``%pose X Y HEADING``: :mod:`simmer.localize.messages`), not robot commands.
It costs no simulated time and is answered in order like any other line."""

DOCUMENT = b"J"
"""Persistent protocol: the first byte of a document frame (the answer to ``%maze``): then the
length as an unsigned 32-bit little-endian number, then that many bytes of UTF-8 JSON."""
DOCUMENT_HEADER = struct.Struct("<cI")
MAX_DOCUMENT_BYTES = 16 * 1024 * 1024
"""Longest document frame (a maze's JSON is a few kilobytes)."""


def decode_meta(data: bytes, size: int) -> Decoded:
    """A localization line (``%...``, line ending removed; ``size``: the bytes it used): one
    reply, whatever commas its JSON has; only the byte limit applies."""
    if (refused := over_limit(len(data), 1)) is not None:
        return refused
    try:
        text = data.decode("utf-8").rstrip("\r")
    except UnicodeDecodeError as exc:
        return Refused(_not_text(exc, "utf-8"), size=size)
    return LocalizationText(text, size)


def frame_document(text: str) -> bytes:
    """A document frame (:data:`DOCUMENT`); ValueError if over :data:`MAX_DOCUMENT_BYTES`."""
    data = text.encode("utf-8")
    if len(data) > MAX_DOCUMENT_BYTES:
        raise ValueError(f"a document of {len(data)} bytes is over {MAX_DOCUMENT_BYTES}")
    return DOCUMENT_HEADER.pack(DOCUMENT, len(data)) + data
