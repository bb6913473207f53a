"""A grading file's mistakes: each refused in one line naming the file, the key and the fix,
before any program runs; through the command line, no traceback."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from grade_support import grading_folder
from simmer.cli import app
from simmer.errors import SweepError
from simmer.grade import load_grading

GOOD_TEAM = "[[team]]\nname = 'A'\nfolder = 'teams/a'\nprogram = 'python3 robot.py'\n"
MISTAKES = [
    # (what the file says, what the line must hold: the key, then the fix)
    ("sedonds = 300", ("unknown key(s) sedonds", "did you mean 'seconds'?")),
    ("seconds = -5", ("seconds:", "more than 0")),
    ("wall_seconds = 1e9", ("wall_seconds:", "MAX_LIMIT_SECONDS")),
    ("rank = 'fastest'", ("rank:", '"score" or "success"')),
    ("videos = -1", ("videos:", "a whole number, 0 or more")),
    ("success = 'import os'", ("success",)),
    ("answer = 5", ("answer:", '"{target}"')),
    ("config = 'nowhere.toml'", ("config: no such file", "nowhere.toml")),
    ("[limits]\nmemory = 100", ("[limits]: unknown key(s) memory", "'memory_mb'")),
    ("[limits]\nmemory_mb = 0", ("[limits] memory_mb:", "at most 65,536 (MAX_LIMIT")),
    ("[limits]\ncpu_seconds = 'a lot'", ("[limits] cpu_seconds:", "a number")),
    ("[limits]\nprocesses = 99999", ("[limits] processes:", "at most 4,096")),
    ("[limits]\nlandlock = 'yes'", ("[limits] landlock:", "true or false")),
    ("[scenarios]\nseeds = 0", ("seeds",)),
    ("[[scenario]]\nseed = -1", ("[[scenario]] 1: seed", "a whole number 0 or more")),
    ("[[team]]\nname = 'B'\nfolder = 'teams/nowhere'\nprogram = 'x'", ("team 'B': folder",)),
    ("[[team]]\nname = 'B'\nfolder = 'teams/a'", ("team 'B': program", "python3 -u robot.py")),
    (
        "[[team]]\nname = 'B'\nfolder = 'teams/a'\nprogram = 'x'\ncolour = 1",
        ("colour", "known: name"),
    ),
    ("[[team]]\nname = ''\nfolder = 'teams/a'\nprogram = 'x'", ("team 2: name", "1 to 40")),
    ("[[team]]\nname = 'A'\nfolder = 'teams/a'\nprogram = 'x'", ("each team's name once",)),
    ("[[team]]\nname = 'B'\nfolder = 'teams/a'\nprogram = 'x'\nconfig = 'no.toml'", ("config",)),
    # a team whose folder holds another's would get the other's program copied into its box
    ("[[team]]\nname = 'All'\nfolder = '.'\nprogram = 'x'", ("team 'All': folder", "side by")),
]


def _course(tmp_path: Path, extra: str) -> Path:
    """A grading file of one good team, with ``extra`` after it (a key at the top if it has
    no table)."""
    path = grading_folder(tmp_path, teams={"A": "print('hello')\n"}, targets=("B1",))
    text = path.read_text(encoding="utf-8")
    if extra.startswith("["):
        if extra.startswith("[scenarios]"):  # replaces the file's own
            text = text.replace('[scenarios]\nseeds = [1]\n"scenario.target" = ["B1"]\n', "")
        if extra.startswith("[[scenario]]"):
            text = text.replace("[scenarios]\n", "[[scenario]]\n", 1).replace(
                'seeds = [1]\n"scenario.target" = ["B1"]\n', extra.split("\n", 1)[1] + "\n"
            )
            extra = ""
        text += "\n" + extra + "\n"
    else:
        key = extra.split(" =", 1)[0]
        text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(f"{key} =")) + "\n"
        text = extra + "\n" + text
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(("extra", "said"), MISTAKES, ids=[m[0] for m in MISTAKES])
def test_each_mistake_is_one_line_naming_the_file_the_key_and_the_fix(
    tmp_path: Path, extra: str, said: tuple[str, ...]
) -> None:
    path = _course(tmp_path, extra)
    with pytest.raises(SweepError) as caught:
        load_grading(path)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    for words in said:
        assert words in message


def test_the_file_as_written_loads(tmp_path: Path) -> None:
    """The mistakes' file without a mistake: the refusals above are the mistakes'."""
    spec = load_grading(_course(tmp_path, "videos = 1"))
    assert [team.name for team in spec.teams] == ["A"]
    assert spec.videos == 1


def test_the_command_line_says_it_in_one_line_and_runs_nothing(tmp_path: Path) -> None:
    path = _course(tmp_path, "[limits]\nmemory = 100")
    result = CliRunner().invoke(app, ["grade", str(path), "-o", str(tmp_path / "out")])
    assert result.exit_code == 1
    lines = [ln for ln in result.output.splitlines() if ln.strip()]
    assert len(lines) == 1, result.output
    assert "Traceback" not in result.output
    assert "GRADING.toml" in lines[0]
    assert "memory_mb" in lines[0]
    assert not (tmp_path / "out").exists()
