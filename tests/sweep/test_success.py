"""A success condition that cannot work is refused before the first run, with the sweep file,
its line and the key (``target < 5`` made every run ``crashed: TypeError``; ``target *
1000000000 == 0`` built a 2 GB string in each), and evaluation builds nothing large."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from simmer.errors import SweepError
from simmer.sweep.success import OUTCOME_FIELDS, PROJECT_FIELDS, TEXT_FIELDS, success_condition

from helpers import EXAMPLES, REPO

POLICIES = REPO / "tests" / "fixtures" / "sweep" / "sweep_policies.py"
RUN = {"reached": True, "collisions": 0, "commands": 12, "target": "B2", "wrong_zone": None}
"""A run's fields as a worker has them: numbers, flags and text."""


@pytest.mark.parametrize(
    "text",
    [
        "target < 5",
        "target * 1000000000 == 0",
        "target + 1 > 0",
        "-wrong_zone < 0",
        "target == 0",
        "(target or 5) * 1000000000 > 0",
        "delivered and (wrong_zone and 1) / 2 > 0",
    ],
)
def test_text_in_arithmetic_or_a_comparison_is_refused(text: str) -> None:
    with pytest.raises(SweepError, match=r"is a zone's name, not a number"):
        success_condition(text)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("not wrong_zone and reached", True),
        ("target and collisions == 0", True),
        ("reached == true and commands * 1000000000 == 12000000000", True),
        ("commands / 0 > 1", False),  # no value: false, as before
        (f"commands * 1{'0' * 300} * 1{'0' * 300} > 1e308", True),  # floats: infinity
    ],
)
def test_numbers_and_tests_of_text_still_work(text: str, expected: bool) -> None:
    assert success_condition(text)(RUN) is expected


def test_a_number_no_float_holds_is_refused() -> None:
    with pytest.raises(SweepError, match="too large a number"):
        success_condition("commands < 1" + "0" * 400)


def test_every_text_field_is_a_field() -> None:
    assert {*OUTCOME_FIELDS, *PROJECT_FIELDS} >= TEXT_FIELDS


@given(
    name=st.sampled_from(sorted({*OUTCOME_FIELDS, *PROJECT_FIELDS} - TEXT_FIELDS)),
    value=st.one_of(
        st.none(),
        st.booleans(),
        st.integers(min_value=-(10**400), max_value=10**400),
        st.floats(allow_nan=True, allow_infinity=True),
    ),
    factor=st.sampled_from(["1", "1000000000", "1e308", "0", "-1e-308"]),
)
def test_an_accepted_condition_never_raises_in_a_run(name: str, value: object, factor: str) -> None:
    for text in (f"{name} * {factor} < {name}", f"-{name} / {factor} == {name} + {factor}"):
        assert success_condition(text)({name: value}) in (True, False)


def test_simmer_sweep_refuses_it_before_the_first_run(tmp_path: Path) -> None:
    shutil.copy(POLICIES, tmp_path)
    shutil.copy(EXAMPLES / "lab1_rover.toml", tmp_path)
    (tmp_path / "sweep.toml").write_text(
        'config = "lab1_rover.toml"\n'
        'policy = "sweep_policies:drive_and_stop"\n'
        "seeds = 2\n"
        'success = "target < 5"\n',
        encoding="utf-8",
    )
    done = subprocess.run(
        [sys.executable, "-m", "simmer", "sweep", "sweep.toml", "--workers", "1"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 1
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("sweep.toml:4: success: 'target < 5': target is a zone's name")
    assert not (tmp_path / "sweep-results").exists()


def test_busy_nan_and_blocked_counts_are_columns_a_condition_may_name() -> None:
    """busy_replies was in report.json only; now results.csv has it, and blocked moves."""
    from simmer import Simulation
    from simmer.sweep.success import flat_outcome, succeeded
    from simmer.world.outcome import Outcome

    for name in ("nan_replies", "busy_replies", "blocked_moves"):
        assert name in OUTCOME_FIELDS
    sim = Simulation.from_config()
    outcome = Outcome.attach(sim)
    sim.command("w0-60")  # into the wall above the start
    sim.command("w0-1")  # refused: the drive is still moving
    sim.run_until_idle()
    report = outcome.report().as_dict()
    fields = flat_outcome(report)
    assert (fields["busy_replies"], fields["nan_replies"], fields["blocked_moves"]) == (1, 0, 1)
    assert succeeded("busy_replies == 1 and blocked_moves == 1", report)
    assert not succeeded("blocked_moves == 0", report)


def test_a_summary_states_the_base_configurations_fixed_noise() -> None:
    """With the lab's bias on, the 0/0 row of an error sweep failed 60 of 60 with no word why:
    the summary now names every error and bias the sweep leaves as the file has it."""
    from simmer.sweep.results import fixed_noise

    from helpers import make_config, noisy_data

    config = make_config(noisy_data())
    fixed = fixed_noise(config, ["drives.w0.error.y", "drives.r0.error.rotation"])
    assert "`drives.w0.bias.rotation = 0.2`" in fixed
    assert "`drives.w0.error.x = 0.02`" in fixed
    assert "`sensors.u0.error = 0.05`" in fixed
    assert not any("w0.error.y" in item or "r0.error.rotation" in item for item in fixed)
    assert fixed_noise(make_config(noisy_data()), ["drives", "sensors"]) == []
