"""``%pose X Y HEADING`` reads its numbers as a command reads its value: decimal, ASCII digits,
within ±MAX_ABS_VALUE (``%pose 1_0 2 3`` and fullwidth or Arabic-Indic digits were accepted,
as ``float()`` reads them, where ``w0-1_0`` is refused)."""

from __future__ import annotations

import math
import socket

import pytest

from link_support import read_frame, serving
from simmer.protocol import decimal_number, parse_command

REFUSED = ["1_0", "\uff11\uff12", "\u0661\u0662", "nan", "inf", "1e400", "2e9", "0x10", " "]


@pytest.mark.parametrize("raw", REFUSED)
def test_a_pose_number_is_read_as_a_commands_value(raw: str) -> None:
    assert decimal_number(raw) is None
    assert parse_command(f"w0-{raw}").error is not None


def test_a_program_gets_nan_for_a_pose_a_command_could_not_hold() -> None:
    lines = [f"%pose {raw} 2 3" for raw in REFUSED[:-1]]
    with (
        serving() as (_runner, link),
        socket.create_connection(("127.0.0.1", link.stream.port), timeout=10) as sock,
    ):
        sock.sendall("".join(f"{line}\n" for line in [*lines, "%pose 10 -2.5e1 90."]).encode())
        replies = [read_frame(sock) for _ in range(len(lines) + 1)]
    assert all(math.isnan(reply[0]) for reply in replies[:-1]), replies
    assert replies[-1] == [0.0]
