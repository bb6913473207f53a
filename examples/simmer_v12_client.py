"""An interactive client in the style of SimMeR v1.2's own (its framed text protocol).

Type commands as you would for the robot: ``u0``, ``w0:6`` (or ``w0-6``), ``r0:-90``, ``xx``,
several at once with commas (``u0,u1,u2``). Each message is sent as one frame (``[u0,u1]``) on
the simulator's message port and the reply frame (``[u0:15.45,u1:3.5]``) is read from its reply
port; each entry is printed, with a warning if it answers a different device than the command.

It needs a simulator speaking the framed protocol: an original SimMeR v1.2 ``config.py``
(``simmer run config.py``, which says "looks like a SimMeR v1.2 config"), a TOML file with
``protocol = "framed"``, or ``simmer run --protocol framed``. Type ``quit`` to leave.
"""

from __future__ import annotations

import os
import socket

HOST = os.environ.get("SIMMER_HOST") or "127.0.0.1"
# SimMeR's ports, 61200 and 61201 unless SIMMER_PORTS moves them (as it does every simmer
# command's): "62000" for 62000, 62001, 62002, or three ports "RX,TX,PORT"
PORTS = [int(port) for port in os.environ.get("SIMMER_PORTS", "61200").split(",")]
PORT_TX = PORTS[0]  # the client transmits here (the simulator's port_rx)
PORT_RX = PORTS[1] if len(PORTS) == 3 else PORTS[0] + 1  # the client receives here (port_tx)
TIMEOUT = 300.0
FRAME_START = "["
FRAME_END = "]"
ENCODING = "ascii"


def packetize(message: str) -> str:
    """Frame what was typed: ``u0, u1`` -> ``[u0,u1]``."""
    commands = [part.strip() for part in message.split(",") if part.strip()]
    return FRAME_START + ",".join(commands) + FRAME_END


def transmit(packet: str) -> None:
    """Send one framed message and close the connection (the simulator then answers)."""
    with socket.create_connection((HOST, PORT_TX), timeout=TIMEOUT) as s:
        s.sendall(packet.encode(ENCODING))


def receive() -> str:
    """Read the reply to the last message; empty if the simulator closed with nothing."""
    data = b""
    with socket.create_connection((HOST, PORT_RX), timeout=TIMEOUT) as s:
        while chunk := s.recv(1024):
            data += chunk
    return data.decode(ENCODING, errors="replace")


def depacketize(reply: str) -> list[tuple[str, str]] | None:
    """``[u0:15.45,w0:True]`` -> ``[("u0", "15.45"), ("w0", "True")]``; None if malformed."""
    start, end = reply.find(FRAME_START), reply.rfind(FRAME_END)
    if start < 0 or end < start:
        return None
    entries = []
    for entry in reply[start + 1 : end].split(","):
        device_id, _, value = entry.partition(":")
        entries.append((device_id, value))
    return entries


def main() -> None:
    """Read commands, send them, print the replies, until 'quit'."""
    print("Commands: u0, w0:6, r0:-90, xx (stop); several with commas. 'quit' leaves.")
    while True:
        try:
            message = input("command> ").strip()
        except EOFError:
            break
        if message in ("quit", "exit"):
            break
        if not message:
            continue
        packet = packetize(message)
        try:
            transmit(packet)
            reply = receive()
        except OSError as exc:
            print(f"cannot reach the simulator at {HOST}:{PORT_TX}/{PORT_RX}: {exc}")
            continue
        entries = depacketize(reply)
        if entries is None:
            print(f"malformed reply {reply!r} to {packet} (is the simulator speaking frames?)")
            continue
        commands = packet[1:-1].split(",")
        for command, (device_id, value) in zip(commands, entries, strict=False):
            check = "" if command[:2] == device_id else f"  (sent {command[:2]}: mismatch!)"
            print(f"{device_id}: {value}{check}")


if __name__ == "__main__":
    main()
