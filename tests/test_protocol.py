"""The pure protocol: parsing, decoding bytes, packing and framing replies."""

from __future__ import annotations

import math
import os
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from simmer.protocol import (
    CACHED_LONG_MESSAGES,
    CACHED_MESSAGE_CHARS,
    MAX_COMMANDS,
    MAX_MESSAGE_BYTES,
    decode_message,
    frame_replies,
    pack_replies,
    parse_command,
    parse_commands,
    parse_message,
    printable,
    read_frame_header,
    unpack_replies,
)

EXAMPLES = int(os.environ.get("SIMMER_HYPOTHESIS_EXAMPLES", "200"))


@pytest.mark.parametrize(
    ("text", "device", "value"),
    [("u0", "u0", 0.0), ("w0-6", "w0", 6.0), ("w0--6", "w0", -6.0), ("r0-1.5e2", "r0", 150.0)],
)
def test_good_commands(text: str, device: str, value: float) -> None:
    command = parse_command(text)
    assert (command.device, command.value, command.error) == (device, value, None)


@pytest.mark.parametrize(
    "text", ["", "u", "w0-abc", "w0-nan", "w0-inf", "w0-1e308", "w06", "w0 6", "w0-"]
)
def test_bad_commands_carry_a_reason(text: str) -> None:
    assert parse_command(text).error


def test_long_messages_are_remembered_a_few_at_a_time_and_never_over_the_limits() -> None:
    """A LiDAR's whole-scan read (some 3 KB, sent again and again) is parsed once while it is
    among the last CACHED_LONG_MESSAGES long messages; a message over MAX_COMMANDS commands is
    parsed each time (no cache holds a message a transport refuses)."""
    scan = ",".join(["l0--2", *(f"l0-{a:.1f}" for a in range(360))])
    assert len(scan) > CACHED_MESSAGE_CHARS
    first = parse_commands(scan)
    assert parse_commands(scan) is first
    assert [c.value for c in first[:3]] == [-2.0, 0.0, 1.0]
    for other in range(CACHED_LONG_MESSAGES):  # pushes the scan out
        parse_commands(f"{scan},u{other}")
    again = parse_commands(scan)
    assert again == first
    assert again is not first
    flood = ",".join(["u0"] * (MAX_COMMANDS + 1))
    one, two = parse_commands(flood), parse_commands(flood)
    assert len(one) == MAX_COMMANDS + 1
    assert one is not two


def test_message_splits_on_commas_and_empty_message_is_one_bad_command() -> None:
    assert [c.device for c in parse_message("u0,u1,w0-12")] == ["u0", "u1", "w0"]
    (empty,) = parse_message("")
    assert empty.error


def test_decode_strips_line_endings() -> None:
    assert decode_message(b"u0,u1\r\n").text == "u0,u1"


def test_non_utf8_gives_one_nan_per_command_and_a_reason() -> None:
    decoded = decode_message(b"u0,\xff\xfe,w0-1")
    assert decoded.text is None
    assert decoded.count == 3
    assert decoded.error is not None
    assert "utf-8" in decoded.error


def test_oversize_message_is_rejected() -> None:
    decoded = decode_message(b"u0," * (MAX_MESSAGE_BYTES // 3 + 1))
    assert decoded.text is None
    assert decoded.count == 1


@pytest.mark.parametrize(("width", "code"), [(4, "<f"), (8, "<d")])
def test_pack_is_little_endian(width: int, code: str) -> None:
    values = [1.5, math.inf, -2.0]
    assert pack_replies(values, width) == b"".join(struct.pack(code, v) for v in values)
    assert unpack_replies(pack_replies(values, width), width) == values


def test_frame_header_says_width_and_count() -> None:
    frame = frame_replies([1.0, 2.0], 8)
    assert frame[:3] == bytes([8, 2, 0])
    assert read_frame_header(frame[:3]) == (8, 2)
    assert unpack_replies(frame[3:], 8) == [1.0, 2.0]
    with pytest.raises(ValueError, match="width"):
        read_frame_header(bytes([5, 1, 0]))
    with pytest.raises(ValueError, match="whole number"):
        unpack_replies(b"\x00" * 5, 4)


@pytest.mark.slow
@settings(max_examples=EXAMPLES, deadline=None)
@given(st.binary(max_size=200))
def test_any_bytes_decode_to_one_reply_per_command(data: bytes) -> None:
    decoded = decode_message(data)
    if decoded.text is None:
        assert decoded.count == data.count(b",") + 1
    else:
        commands = parse_message(decoded.text)
        assert len(commands) == decoded.text.count(",") + 1
        for command in commands:
            assert command.error is not None or math.isfinite(command.value)


@pytest.mark.slow
@settings(max_examples=EXAMPLES, deadline=None)
@given(
    st.text(alphabet="uwrmx0123", min_size=2, max_size=2),
    st.floats(allow_nan=False, allow_infinity=False, min_value=-1e9, max_value=1e9),
)
def test_valid_commands_round_trip(device: str, value: float) -> None:
    command = parse_command(f"{device}-{value!r}")
    assert command.error is None
    assert (command.device, command.value) == (device, value)


@pytest.mark.parametrize("text", ["u0-٥", "w0-６", "w0-١٢", "w0-\u20075", "w0-5\u0665"])
@pytest.mark.parametrize("lenient", [False, True])
def test_digits_outside_ascii_are_not_numbers(text: str, lenient: bool) -> None:
    command = parse_command(text, lenient=lenient)
    assert command.error is not None
    assert "ASCII" in command.error


def test_printable_escapes_only_what_is_not_printable() -> None:
    assert printable("w0-6 ٥ é") == "w0-6 ٥ é"
    assert printable("a\x1bb\u202ec\n") == "a\\x1bb\\u202ec\\n"
    assert printable(repr("\x1b")) == repr("\x1b")  # already escaped: unchanged


def test_a_frame_never_says_more_values_than_its_count_can() -> None:
    assert len(frame_replies([0.0] * 0xFFFF)) == 3 + 4 * 0xFFFF
    with pytest.raises(ValueError, match="do not fit"):
        frame_replies([0.0] * 0x10000)
