"""``simmer.ports.Ports``: the one place that says which ports a run listens on."""

from __future__ import annotations

from simmer.ports import FREE, PORT_RX, PORT_TX, STREAM_PORT, Ports


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
