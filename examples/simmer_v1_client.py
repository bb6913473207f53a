"""A control program written the way SimMeR's own example clients are: send a message on one
port and close, then open the other port and read the reply (packed floats).

Unlike the original simulator, this one holds the reply connection open until the reply is
ready, so no ``sleep`` is needed between the two steps. Start ``simmer run``, then run
``python examples/simmer_v1_client.py``. Set REPLY_BYTES to 8 for a v1.0 configuration
(``reply_bytes = 8``), 4 for v1.1 (the default).
"""

from __future__ import annotations

import os
import socket
import struct
import sys

HOST = os.environ.get("SIMMER_HOST") or "127.0.0.1"
# SimMeR's ports, 61200 and 61201 unless SIMMER_PORTS moves them (as it does every simmer
# command's): "62000" for 62000, 62001, 62002, or three ports "RX,TX,PORT"
PORTS = [int(port) for port in os.environ.get("SIMMER_PORTS", "61200").split(",")]
PORT_TX = PORTS[0]  # the client transmits here (the simulator's port_rx)
PORT_RX = PORTS[1] if len(PORTS) == 3 else PORTS[0] + 1  # the client receives here (port_tx)
REPLY_BYTES = 4


def transmit(data: str) -> None:
    """Send one message to the simulator."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.connect((HOST, PORT_TX))
        s.sendall(data.encode("utf-8"))


def receive() -> list[float]:
    """Read the reply to the last message."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.connect((HOST, PORT_RX))
        response_raw = b""
        while chunk := s.recv(1024):
            response_raw += chunk
    return depack(response_raw)


def depack(data: bytes) -> list[float]:
    """Unpack little-endian floats of REPLY_BYTES each."""
    code = "<f" if REPLY_BYTES == 4 else "<d"
    return [value for (value,) in struct.iter_unpack(code, data)]


def send(data: str) -> list[float]:
    """Transmit a message and return its reply."""
    transmit(data)
    return receive()


def main() -> None:
    """Type commands; an empty line quits."""
    print("Type commands such as u0 or w0-6 (empty line to quit).")
    for line in sys.stdin:
        command = line.strip()
        if not command:
            break
        print(f"{command} -> {send(command)}")


if __name__ == "__main__":
    main()
