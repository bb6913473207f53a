"""``simmer.ports.Ports``: the one place that says which ports a run listens on."""

from __future__ import annotations

import pytest

from simmer.client import Address, address
from simmer.errors import ConnectionFailed, FlagError, PortsError
from simmer.lockstep import program_environment
from simmer.options import RunOptions
from simmer.ports import (
    FREE,
    PORT_RX,
    PORT_TX,
    PORTS_VARIABLE,
    STREAM_PORT,
    Ports,
    environment_ports,
    parse_ports,
)


def test_the_configurations_ports_are_taken_where_none_is_named() -> None:
    assert Ports().resolve(5000, 5001) == (5000, 5001, STREAM_PORT)
    assert Ports(rx=6000, stream=FREE).resolve(PORT_RX, PORT_TX) == (6000, PORT_TX, 0)
    assert Ports.free().resolve(5000, 5001) == (0, 0, 0)


def test_a_program_takes_free_ports_unless_a_flag_names_one() -> None:
    assert Ports.from_flags(None, None, None, program=True) == Ports.free()
    assert Ports.from_flags(7000, None, 7002, program=True) == Ports(7000, FREE, 7002)
    assert Ports.from_flags(None, 0, None, program=False) == Ports(None, FREE, None)


def test_only_numbered_two_port_ports_are_configuration_settings() -> None:
    assert Ports(5000, FREE, 5002).settings() == {"port_rx": 5000}
    assert Ports(None, 5001, FREE).settings() == {"port_tx": 5001}
    assert Ports.free().settings() == {}


def test_one_setting_names_all_three_ports() -> None:
    assert parse_ports("62000") == Ports(62000, 62001, 62002)
    assert parse_ports(" 7000, 7005 ,7009") == Ports(7000, 7005, 7009)
    assert parse_ports("AUTO") == Ports.free()


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("62000,62001", "not ports"),
        ("sixty", "not ports"),
        ("-5", "not ports"),
        ("65534", "from 1 to 65535"),
        ("0,1,2", "from 1 to 65535"),
        ("7000,7000,7001", "must differ"),
    ],
)
def test_a_setting_that_names_no_three_ports_is_one_line_with_the_fix(text: str, said: str) -> None:
    with pytest.raises(PortsError) as raised:
        parse_ports(text, PORTS_VARIABLE)
    message = str(raised.value)
    assert message.startswith(f"SIMMER_PORTS={text!r}: ")
    assert said in message
    assert "62000" in message
    assert "auto" in message
    assert "\n" not in message


def test_the_environment_moves_the_ports_unless_a_flag_names_one() -> None:
    assert environment_ports({}) is None
    assert environment_ports({PORTS_VARIABLE: " "}) is None
    chosen = environment_ports({PORTS_VARIABLE: "62000"})
    assert chosen == Ports(62000, 62001, 62002)
    assert Ports.from_flags(None, 5001, None, program=False, chosen=chosen) == Ports(
        62000, 5001, 62002
    )
    assert Ports.from_flags(None, None, None, program=True, chosen=chosen) == chosen


def test_run_options_take_the_flag_over_the_variable_and_a_program_keeps_free_ports() -> None:
    environ = {PORTS_VARIABLE: "62000"}
    assert RunOptions.from_flags(environ=environ).ports == Ports(62000, 62001, 62002)
    assert RunOptions.from_flags(ports="63000", environ=environ).ports.rx == 63000
    assert RunOptions.from_flags(ports="auto", port=5).ports == Ports(FREE, FREE, 5)
    assert RunOptions.from_flags(program="python x.py", environ=environ).ports == Ports.free()
    with pytest.raises(FlagError, match="SIMMER_PORTS='x'"):
        RunOptions.from_flags(environ={PORTS_VARIABLE: "x"})


def test_the_client_reads_the_one_variable_and_the_run_sets_it_for_its_program(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    for name in ("SIMMER_PORT", "SIMMER_PORT_RX", "SIMMER_PORT_TX", "SIMMER_HOST"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv(PORTS_VARIABLE, "62000")
    assert address() == Address("127.0.0.1", 62000, 62001, 62002)
    monkeypatch.setenv("SIMMER_PORT", "7")  # one port named on its own still wins
    assert address().port == 7
    env = program_environment({"port_rx": 1, "port_tx": 2, "stream": 3}, base={})
    assert env[PORTS_VARIABLE] == "1,2,3"
    monkeypatch.setenv(PORTS_VARIABLE, "auto")
    with pytest.raises(ConnectionFailed, match="the three ports that simmer run printed"):
        address()
