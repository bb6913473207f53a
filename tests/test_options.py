"""``RunOptions.from_flags``: the decisions ``simmer run`` makes about its flags, without typer."""

from __future__ import annotations

from pathlib import Path

import pytest

from simmer.errors import FlagError
from simmer.lockstep import MAX_ANSWER
from simmer.options import MAX_RECORDING_BYTES, RunOptions
from simmer.ports import FREE, Ports


def test_no_flags_are_a_window_in_real_time_on_the_configurations_ports() -> None:
    options = RunOptions.from_flags()
    assert options == RunOptions(window=True)
    assert (options.clock, options.speed, options.ports, options.host) == (
        "realtime",
        1.0,
        Ports(),
        None,
    )
    assert options.record_limit == MAX_RECORDING_BYTES


def test_a_program_implies_lockstep_free_ports_and_headless_max_speed() -> None:
    options = RunOptions.from_flags(headless=True, program="python robot.py")
    assert options.lockstep
    assert options.ports == Ports.free()
    assert options.speed is None
    assert not options.window


def test_a_program_with_a_window_keeps_real_time_speed() -> None:
    assert RunOptions.from_flags(program="python robot.py").speed == 1.0


def test_flags_given_win_over_what_a_program_implies() -> None:
    options = RunOptions.from_flags(
        headless=True, program="p", clock="realtime", speed="2", port_rx=5000, port=5002
    )
    assert (options.clock, options.speed) == ("realtime", 2.0)
    assert options.ports == Ports(5000, FREE, 5002)


def test_lockstep_without_a_program_is_kept_and_ports_stay_the_configurations() -> None:
    options = RunOptions.from_flags(clock="lockstep", port_tx=0)
    assert options.lockstep
    assert options.ports == Ports(None, FREE, None)


@pytest.mark.parametrize(
    ("speed", "words"),
    [
        ("fast", "speed is a number (1 = real time) or 'max', not 'fast'"),
        ("-1", "speed must be more than 0"),
        ("1e-300", "1e-300: from 0.01 to 1000 times real time, or 'max' (SPEED_RANGE"),
        ("2000", "2000: from 0.01 to 1000 times real time"),
    ],
)
def test_a_speed_out_of_range_is_refused_naming_the_flag(speed: str, words: str) -> None:
    with pytest.raises(FlagError) as refused:
        RunOptions.from_flags(speed=speed)
    assert refused.value.flag == "--speed"
    assert words in refused.value.message


def test_max_speed_is_as_fast_as_possible() -> None:
    assert RunOptions.from_flags(speed="MAX").speed is None


def test_an_answer_needs_a_program_and_is_bounded() -> None:
    with pytest.raises(FlagError, match="give --program too") as refused:
        RunOptions.from_flags(answer="B2")
    assert refused.value.flag is None
    with pytest.raises(FlagError, match=f"at most {MAX_ANSWER:,}") as refused:
        RunOptions.from_flags(program="p", answer="x" * (MAX_ANSWER + 1))
    assert refused.value.flag == "--answer"


def test_an_unknown_clock_is_refused() -> None:
    with pytest.raises(FlagError, match="realtime or lockstep, not 'wall'"):
        RunOptions.from_flags(clock="wall")


def test_the_record_limit_is_given_in_megabytes(tmp_path: Path) -> None:
    options = RunOptions.from_flags(record=tmp_path / "run", record_limit_mb=1.5)
    assert options.record_limit == 3 * 2**19
    assert options.record == tmp_path / "run"


def test_the_answer_takes_the_runs_target() -> None:
    options = RunOptions.from_flags(program="p", answer="zone {target}")
    assert options.for_target("B2").answer == "zone B2"
    assert options.for_target(None) is options
