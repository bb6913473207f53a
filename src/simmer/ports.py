"""SimMeR's standard ports, written in one place (the original's, and the persistent one)."""

from __future__ import annotations

PORT_RX = 61200
"""SimMeR's two-port scheme: messages arrive here (a client transmits to it)."""
PORT_TX = 61201
"""SimMeR's two-port scheme: replies leave from here (a client receives from it)."""
STREAM_PORT = 61202
"""The persistent protocol (``simmer.client``)."""
