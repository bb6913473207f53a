"""What ``simmer`` prints of a user's data stays as written: no console markup, no emoji codes
(``robot.toml:100:`` once printed ``robot.toml💯``), in its own messages and in typer's."""

from __future__ import annotations

from pathlib import Path

import pytest

from helpers import run_simmer


@pytest.mark.parametrize(("line", "code"), [(100, ":100:"), (1234, ":1234:")])
def test_a_problems_line_number_is_not_an_emoji(tmp_path: Path, line: int, code: str) -> None:
    path = tmp_path / "robot.toml"
    path.write_text("# a comment\n" * (line - 1) + "nonsense_key = 1\n", encoding="utf-8")
    done = run_simmer("check", "robot.toml", cwd=tmp_path)
    assert done.returncode == 1
    assert f"robot.toml{code} nonsense_key: unknown key" in done.stderr
    assert "\N{HUNDRED POINTS SYMBOL}" not in done.stderr
    assert "\N{INPUT SYMBOL FOR NUMBERS}" not in done.stderr


def test_a_flags_value_is_printed_as_given(tmp_path: Path) -> None:
    done = run_simmer("table", "--headings", "a:b:c", "-o", "t.npz", cwd=tmp_path)
    assert done.returncode == 1
    assert "headings 'a:b:c'" in done.stderr
    assert "Traceback" not in done.stderr


def test_markup_in_a_path_is_printed_as_given(tmp_path: Path) -> None:
    folder = tmp_path / "[red]x"
    folder.mkdir()
    (folder / "robot.toml").write_text("nonsense_key = 1\n", encoding="utf-8")
    done = run_simmer("check", str(folder / "robot.toml"), cwd=tmp_path)
    assert done.returncode == 1
    assert "1 problem in " + str(folder / "robot.toml") in done.stderr
    assert "Traceback" not in done.stderr


def test_typers_own_errors_keep_the_value_as_given(tmp_path: Path) -> None:
    done = run_simmer("run", "--headless", "--clock", ":100:", cwd=tmp_path)
    assert done.returncode == 2
    assert "':100:' is not one of" in done.stderr
