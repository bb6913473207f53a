"""A sweep file's numbers are checked before any arithmetic: any float (±1e308, infinities,
NaN, subnormals) or integer a TOML file can hold gives a sweep that runs or one plain
SweepError, never a traceback (``{uniform = [-1e308, 1e308]}`` was an OverflowError)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from simmer.errors import SweepError
from simmer.sweep import spec as sweep_spec
from simmer.sweep.spec import SweepSpec, load_sweep

from helpers import EXAMPLES

EDGES = [0.0, -0.0, 5e-324, -5e-324, 1e-308, 1e308, -1e308, math.inf, -math.inf, math.nan]
NUMBERS = st.one_of(
    st.sampled_from(EDGES),
    st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True),
    st.integers(min_value=-(10**400), max_value=10**400),
    st.integers(min_value=-(2**64), max_value=2**64),
)


def toml_number(value: float) -> str:
    """``value`` as TOML writes it (``inf``, ``nan``, an integer of any length)."""
    if isinstance(value, int):
        return str(value)
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return repr(value)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with the lab rover, where each example writes its sweep file."""
    path = tmp_path_factory.mktemp("numbers")
    (path / "rover.toml").write_text(
        (EXAMPLES / "lab1_rover.toml").read_text(encoding="utf-8"), encoding="utf-8"
    )
    return path


def loaded(folder: Path, body: str) -> SweepSpec | None:
    """The sweep of ``body`` (after a config and a policy), or None if it is refused with a
    one-line SweepError; any other exception fails the test."""
    path = folder / "sweep.toml"
    path.write_text(f'config = "rover.toml"\npolicy = "a:b"\n{body}\n', encoding="utf-8")
    refused: list[str] = []
    try:
        return load_sweep(path)
    except SweepError as exc:
        refused.append(str(exc))
    assert "\n" not in refused[0]
    return None


@settings(
    max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(kind=st.sampled_from(["uniform", "normal"]), first=NUMBERS, second=NUMBERS)
def test_a_distributions_numbers_draw_or_are_refused(
    folder: Path, kind: str, first: float, second: float
) -> None:
    body = (
        f'[sample]\ncount = 3\n"drives.w0.error.y" = '
        f"{{{kind} = [{toml_number(first)}, {toml_number(second)}]}}"
    )
    spec = loaded(folder, body)
    if spec is None:
        return
    assert all(abs(v) <= sweep_spec.MAX_SAMPLE_NUMBER for v in (first, second))
    ((_, distribution),) = spec.sample
    drawn = [value for (value,) in spec.draws()]
    assert all(math.isfinite(value) for value in [*drawn, distribution.typical()])


@settings(
    max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(name=st.sampled_from(["seconds", "wall_seconds"]), value=NUMBERS)
def test_a_runs_time_limits_are_finite_and_bounded(folder: Path, name: str, value: float) -> None:
    spec = loaded(folder, f"{name} = {toml_number(value)}")
    if spec is not None:
        limit = spec.seconds if name == "seconds" else spec.wall_seconds
        assert limit is not None
        assert 0 < limit <= sweep_spec.MAX_LIMIT_SECONDS


@settings(
    max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(value=NUMBERS)
def test_a_grids_numbers_are_checked_as_settings(folder: Path, value: float) -> None:
    spec = loaded(folder, f'[grid]\n"drives.w0.error.y" = [{toml_number(value)}]')
    if spec is not None:
        refused: list[str] = []
        try:
            spec.check_settings()
        except SweepError as exc:
            refused.append(str(exc))
        assert all("\n" not in message for message in refused)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(values=st.lists(NUMBERS, min_size=1, max_size=3))
def test_counts_and_seeds_are_checked(folder: Path, values: list[float]) -> None:
    listed = ", ".join(map(toml_number, values))
    first = toml_number(values[0])
    sampled = '"drives.w0.error.y" = {uniform = [0, 1]}'
    for body in (
        f"seeds = [{listed}]",
        f"seeds = {first}",
        f"videos = {first}",
        f"sample_seed = {first}",
        f"[sample]\ncount = {first}\n{sampled}",
    ):
        spec = loaded(folder, body)
        if spec is not None:
            assert spec.run_count >= 1


@pytest.mark.slow
def test_the_issues_sweep_is_one_plain_line(tmp_path: Path) -> None:
    (tmp_path / "rover.toml").write_text(
        (EXAMPLES / "lab1_rover.toml").read_text(encoding="utf-8"), encoding="utf-8"
    )
    (tmp_path / "sweep.toml").write_text(
        'config = "rover.toml"\npolicy = "a:b"\n\n[sample]\ncount = 2\n'
        '"drives.w0.error.y" = {uniform = [-1e308, 1e308]}\n',
        encoding="utf-8",
    )
    done = subprocess.run(
        [sys.executable, "-m", "simmer", "sweep", "sweep.toml"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 1
    assert "Traceback" not in done.stderr
    assert "MAX_SAMPLE_NUMBER" in done.stderr
    assert "drives.w0.error.y" in done.stderr


def test_an_integer_too_long_for_python_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "sweep.toml"
    path.write_text(f"seeds = {'9' * 5000}\n", encoding="utf-8")
    with pytest.raises(SweepError, match="a number too long to read") as refused:
        load_sweep(path)
    assert "\n" not in str(refused.value)
