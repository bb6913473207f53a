"""simmer.client over every transport, and its errors."""

from __future__ import annotations

import math
import socket
import subprocess
import sys

import numpy as np
import pytest

from link_support import free_port, serving
from simmer.client import connect
from simmer.console import format_reply, run_console
from simmer.errors import ConnectionFailed, ReplyTimeout
from simmer.world import Simulation
from simmer.world.outcome import Outcome

pytestmark = pytest.mark.timeout(60)


def test_same_calls_over_every_transport() -> None:
    with serving(speed=None, serial=True) as (runner, link):
        assert link.serial is not None
        clients = [
            connect(port=link.stream.port),
            connect(
                scheme="two-port", port_rx=link.two_port.port_rx, port_tx=link.two_port.port_tx
            ),
            connect(serial=link.serial.path, timeout=5),
        ]
        for client in clients:
            with client:
                assert client.read("u1") == pytest.approx(3.5)
                assert client.send("u1,zz")[0] == pytest.approx(3.5)
                assert math.isnan(client.send("u1,zz")[1])
                assert client.drive("w0", 1) == math.inf
                client.wait_idle()
                assert client.read("m0") > 0
        assert runner.sim.robot.pose.y == pytest.approx(39.0)


def test_refused_connection_is_connection_failed() -> None:
    port = free_port()
    with pytest.raises(ConnectionFailed, match="simmer run"):
        connect(port=port)
    client = connect(scheme="two-port", port_rx=port, port_tx=free_port())
    with pytest.raises(ConnectionFailed):
        client.send("u0")
    with pytest.raises(ConnectionFailed, match="serial"):
        connect(serial="/nonexistent/tty")


def test_silent_server_is_reply_timeout() -> None:
    with socket.create_server(("127.0.0.1", 0)) as server:
        client = connect(port=server.getsockname()[1], timeout=0.2)
        conn, _ = server.accept()
        with conn, client, pytest.raises(ReplyTimeout):
            client.send("u0")


def test_console_prints_replies() -> None:
    lines = iter(["u1", "", "w0-abc", "quit"])
    shown: list[str] = []
    with serving() as (_, link), connect(port=link.stream.port) as client:
        run_console(client, read=lambda _: next(lines), echo=shown.append, history=False)
    assert shown[1] == "u1: 3.500"
    assert shown[2] == "w0-abc: nan"
    assert format_reply(math.inf) == "+inf (accepted)"


def test_importing_the_client_does_not_load_the_simulator() -> None:
    """A control program pays only for the link: no NumPy, Numba or pydantic."""

    code = (
        "import sys, simmer.client\n"
        "heavy = [m for m in ('numpy', 'numba', 'pydantic', 'simmer.world') if m in sys.modules]\n"
        "print(','.join(heavy))"
    )
    command = [sys.executable, "-c", code]
    result = subprocess.run(command, capture_output=True, text=True, check=True)
    assert result.stdout.strip() == ""


def test_wait_idle_in_real_time_waits_on_the_simulator_without_busy_polls() -> None:
    sim = Simulation.from_config()
    outcome = Outcome.attach(sim)
    with serving(sim, speed=1.0) as (_, link), connect(port=link.stream.port) as robot:
        assert robot.drive("w0", 1) == math.inf  # a sixth of a second of motion
        robot.wait_idle()
        assert robot.drive("w0", 0) == math.inf  # done: accepted at once
    report = outcome.report()  # the loop thread has stopped
    assert (report.busy_replies, report.nan_replies) == (0, 0)
    assert report.messages == 3  # w0-1, the one w0-0 that confirms the wait, and ours
    assert sim.robot.pose.y == pytest.approx(41.0)


@pytest.mark.slow
@pytest.mark.parametrize("protocol", ["packed", "framed"])
def test_a_lidar_scan_reads_whole_over_every_transport(protocol: str) -> None:
    from helpers import default_data, make_sim

    data = default_data() | {"protocol": protocol, "str_encoding": "ascii"}
    quiet = {"range_error": 0, "range_error_proportional": 0, "angular_jitter": 0, "dropout": 0}
    data["sensors"]["l0"] = {"type": "lidar", "position": [0, 0], "beams": 180} | quiet
    sim = make_sim(data)
    want = sim.expected([sim.robot.pose], ["l0"])[0]  # the robot stands still: every scan
    framed = protocol == "framed"
    with serving(sim, speed=None, serial=True) as (_, link):
        assert link.serial is not None
        clients = [
            connect(
                scheme="two-port",
                port_rx=link.two_port.port_rx,
                port_tx=link.two_port.port_tx,
                framed=framed,
            ),
            connect(serial=link.serial.path, timeout=5, framed=framed),
        ]
        if not framed:
            clients.append(connect(port=link.stream.port))
        for client in clients:
            with client:
                first = client.scan("l0")
                angles, distances = client.scan("l0")
                assert first.number >= 1
                np.testing.assert_array_equal(angles, np.arange(180) * 2.0)
                # framed text: 3 decimals; packed: float32 (every transport here), exact to it
                tolerance = 5e-4 if framed else 0.0
                expect = want if framed else want.astype(np.float32)
                np.testing.assert_allclose(distances, expect, rtol=0, atol=tolerance)
                assert math.isnan(client.read("l0-400"))
