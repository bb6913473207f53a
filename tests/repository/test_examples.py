"""The lab's example control programs, run against a live simulator."""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from types import ModuleType

import pytest
from typer.testing import CliRunner

from link_support import run_program, serving
from simmer.cli import app
from simmer.config import load_config
from simmer.config.overrides import with_overrides
from simmer.world import Simulation
from simmer.world.events import BeliefEvent, EstimateEvent, Event
from simmer.world.outcome import Outcome

from helpers import EXAMPLES, default_data, make_sim

pytestmark = pytest.mark.timeout(90)


def load(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def test_dead_reckoning_reaches_the_block(capsys: pytest.CaptureFixture[str]) -> None:
    with serving(speed=None) as (runner, link):
        readings = load("dead_reckoning").main(["--port", str(link.stream.port)])
        pose = runner.sim.robot.pose
    assert math.dist((pose.x, pose.y), (66, 12)) < 0.5
    assert readings[-1][0] == pytest.approx(3.0, abs=0.2)
    assert "u3" in capsys.readouterr().out


def test_obstacle_avoidance_stops_short_of_the_wall() -> None:
    """On the lab rover without noise it stops within a step of 2 in from the wall ahead,
    without touching it (its nose is 1.5 in ahead of the front sensor)."""
    sim = Simulation.from_config()
    outcome = Outcome.attach(sim)
    with serving(sim, speed=None) as (runner, link):
        steps = load("obstacle_avoidance").main(["--port", str(link.stream.port)])
        reading = runner.bus.submit("u0,u1,u2,u3", "test").result(timeout=5)
    assert 0 < steps < 200
    assert 2.0 - 1e-9 <= min(reading) < 2.5  # (steps of 0.5 in add up to 2 in to 1e-12)
    assert outcome.collisions == 0


@pytest.mark.slow
def test_the_particle_filter_example_localizes_and_shows_its_cloud() -> None:
    """particle_filter.py, run as the localization page says (the Lab 1 rover from the start
    1,6,90): a show of its cloud at each reading (at most 2,000 particles, every fourth of
    4,000, fewer as they agree), and the run's outcome says the reported estimate localized."""
    config = with_overrides(load_config(EXAMPLES / "lab1_rover.toml"), {"scenario.start": "1,6,90"})
    sim = Simulation(config, seed=3)
    outcome = Outcome.attach(sim)
    events: list[Event] = []
    sim.add_observer(events.append)
    rover = EXAMPLES / "lab1_rover.toml"
    program = f"{sys.executable} {EXAMPLES / 'particle_filter.py'} {rover} --moves 2"
    assert run_program(sim, program).exit_status == 0
    shown = [json.loads(e.belief) for e in events if isinstance(e, BeliefEvent)]
    assert len(shown) == 3  # a reading before each of 2 moves, and one after the last
    counts = [len(belief["particles"]) for belief in shown]
    assert all(0 < count <= 2000 for count in counts), counts
    assert counts[-1] < counts[0], counts  # fewer particles once they agree (KLD-sampling)
    report = outcome.report().localization
    assert report is not None
    assert report.localized_at is not None
    last = [e for e in events if isinstance(e, EstimateEvent)][-1]
    assert math.dist(last.pose[:2], last.truth[:2]) < 3.0


@pytest.mark.parametrize("width", [4, 8])
def test_original_style_client_example(width: int, monkeypatch: pytest.MonkeyPatch) -> None:
    data = default_data()
    data["reply_bytes"] = width
    client = load("simmer_v1_client")
    with serving(make_sim(data)) as (_, link):
        monkeypatch.setattr(client, "PORT_TX", link.two_port.port_rx)
        monkeypatch.setattr(client, "PORT_RX", link.two_port.port_tx)
        monkeypatch.setattr(client, "REPLY_BYTES", width)
        assert client.send("u1,w0-1") == [pytest.approx(3.5), math.inf]


def test_v12_style_client_example(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    data = default_data() | {"protocol": "framed", "str_encoding": "ascii"}
    client = load("simmer_v12_client")
    typed = iter(["u0, u1", "w0:6", "zz", "quit"])
    with serving(make_sim(data)) as (_, link):
        monkeypatch.setattr(client, "PORT_TX", link.two_port.port_rx)
        monkeypatch.setattr(client, "PORT_RX", link.two_port.port_tx)
        monkeypatch.setattr("builtins.input", lambda _prompt: next(typed))
        client.main()
    shown = capsys.readouterr().out.splitlines()
    assert shown[1:] == ["u0: 39.5", "u1: 3.5", "w0: True", "zz: Not Found"]


def test_cli_run_headless_serves_until_the_time_limit() -> None:
    result = CliRunner().invoke(
        app,
        ["run", "--headless", "--speed", "max", "--seconds", "1", "--seed", "7", "--port", "0",
         "--port-rx", "0", "--port-tx", "0"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "persistent TCP" in result.output
    assert "replies as packed 4-byte floats" in result.output
    assert "Noise: none (every error and bias is 0)" in result.output  # the default is noise-free
    framed = CliRunner().invoke(
        app,
        ["run", "--headless", "--speed", "max", "--seconds", "0.1", "--port", "0",
         "--port-rx", "0", "--port-tx", "0", "--protocol", "framed"],
    )  # fmt: skip
    assert framed.exit_code == 0, framed.output
    assert "replies in SimMeR v1.2 framed text" in framed.output
    bad = CliRunner().invoke(app, ["run", "--headless", "--speed", "fast"])
    assert bad.exit_code != 0


@pytest.mark.slow
def test_the_lidar_localization_example_localizes_from_the_start() -> None:
    """lidar_localization.py on lidar_rover.toml, as its docstring runs it: the particles,
    weighed by scans against the LiDAR's table, find the robot and keep it to the end."""
    config = EXAMPLES / "lidar_rover.toml"
    sim = Simulation.from_config(config)
    outcome = Outcome.attach(sim)
    program = f"{sys.executable} {EXAMPLES / 'lidar_localization.py'} {config} --no-show"
    assert run_program(sim, program).exit_status == 0
    report = outcome.report().localization
    assert report is not None
    assert report.localized_at is not None
    assert report.localized_at < 5.0  # 0.38 s: the first scan, from the start cell
