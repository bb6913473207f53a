"""The time-of-flight, IMU and encoder kinds answer in every protocol: the persistent one's
frames, the two-port scheme's packed float32 (SimMeR v1.1) and float64 (v1.0), and v1.2's
framed text over the two-port scheme and a real pseudo-terminal; each reply is the one the
simulation itself gives, as wide as the protocol carries it."""

from __future__ import annotations

import struct

import pytest
import serial

from link_support import read_frame, serving, stream, two_port_raw, two_port_send
from simmer.protocol import framed_value
from simmer.world import Simulation

from helpers import default_data, make_config

pytestmark = pytest.mark.timeout(60)

MESSAGE = "t0,t1,t2,t3,i0-0,i0-1,i0-2,e0,e1,e1-1,e1"
"""Every new kind's every reading: a wall in reach (inches, millimetres), both presets' value
for nothing in reach, the IMU's three axes, both wheels' counts and a reset."""


def rover(**settings: object) -> Simulation:
    """The default rover with the new kinds (noise off, IMU biases on), driven 7.3 in ahead
    and turned, then left standing: its readings no longer change as time passes."""
    data = default_data() | {"simulate_list": []} | settings
    quiet = {"type": "tof", "error": 0.0, "error_constant": 0.0, "fov": 1.0}
    data["sensors"] |= {
        "t0": quiet | {"position": [0, 4]},
        "t1": quiet | {"position": [0, 4], "units": "mm"},
        "t2": quiet | {"rotation": -90, "max_range": 5.0},  # the wall 13.3 in away: beyond
        "t3": quiet | {"rotation": -90, "max_range": 5.0, "preset": "vl53l1x"},
        "i0": {
            "type": "imu",
            "gyro_noise_density": 0.0,
            "gyro_bias": 0.25,
            "gyro_bias_walk": 0.0,
            "accel_noise_density": [0.0, 0.0],
            "accel_bias": [1.5, -2.125],
            "accel_bias_walk": [0.0, 0.0],
        },
        "e0": {"type": "encoder", "wheel": "left"},
        "e1": {"type": "encoder", "wheel": "right"},
    }
    sim = Simulation(make_config(data))
    for message in ("w0-7.3", "r0--90"):
        sim.command(message)
        assert sim.run_until_idle()
    sim.step(5)
    return sim


def expected(**settings: object) -> tuple[list[float], list[float]]:
    """What the rover answers to MESSAGE, and to MESSAGE again (its right wheel reset)."""
    sim = rover(**settings)
    first, second = sim.command(MESSAGE), sim.command(MESSAGE)
    assert first[2:4] == [8190.0, -1.0]  # both presets' value for nothing in reach
    assert first[9] == first[8] != 0.0  # read and reset
    assert first[10] == second[8] == 0.0
    return first, second


def float32(values: list[float]) -> list[float]:
    return [struct.unpack("<f", struct.pack("<f", v))[0] for v in values]


def test_the_persistent_protocol_and_packed_two_port_carry_every_reading() -> None:
    first, second = expected()
    with serving(rover()) as (_, link):
        with stream(link.stream.port) as sock:
            sock.sendall(MESSAGE.encode() + b"\n")
            assert read_frame(sock) == float32(first)
        assert two_port_send(link, MESSAGE.encode()) == float32(second)


def test_the_v10_width_carries_every_reading_exactly() -> None:
    first, second = expected(reply_bytes=8)
    with serving(rover(reply_bytes=8)) as (_, link):
        assert two_port_send(link, MESSAGE.encode(), width=8) == first
        with stream(link.stream.port) as sock:
            sock.sendall(MESSAGE.encode() + b"\n")
            assert read_frame(sock) == second


def framed_entries(reply: bytes) -> list[float]:
    text = reply.decode("ascii")
    assert text.startswith("[")
    assert text.endswith("]")
    entries = text[1:-1].split(",")
    assert [e.split(":")[0] for e in entries] == [c[:2] for c in MESSAGE.split(",")]
    return [framed_value(e.split(":", 1)[1]) for e in entries]


FRAMED = {"protocol": "framed", "str_encoding": "ascii"}


def test_v12_framed_text_carries_every_reading_over_two_ports_and_serial() -> None:
    first, second = ([round(v, 3) for v in values] for values in expected(**FRAMED))
    request = f"[{MESSAGE.replace('-', ':')}]".encode()
    with serving(rover(**FRAMED), serial=True, silence=0.0) as (_, link):
        assert framed_entries(two_port_raw(link, request)) == first
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(request)
            assert framed_entries(port.read_until(b"]")) == second
