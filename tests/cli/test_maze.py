"""``simmer maze`` as a user types it (docs/mazes.md): list, show with a PNG, generate writing
the same bytes twice, and a broken maze file refused in one line."""

from __future__ import annotations

from pathlib import Path

import pygame
import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.config.mazes import COURSE_MAZES, read_maze


def invoke(*args: str | Path) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["maze", *map(str, args)], terminal_width=120)
    return result.exit_code, result.output


def test_list_names_the_course_mazes() -> None:
    code, text = invoke("list")
    assert code == 0, text
    assert [line.split(":")[0] for line in text.splitlines()] == list(COURSE_MAZES)


def test_show_prints_the_picture_and_draws_it(tmp_path: Path) -> None:
    png = tmp_path / "mie444.png"
    code, text = invoke("show", "mie444", "--png", png)
    assert code == 0, text
    assert "LL..#1#2" in text.splitlines()  # the course maze's top row, as docs/mazes.md has it
    assert "ambiguity" in text
    image = pygame.image.load(str(png))
    width, height = image.get_size()
    assert width > 200
    assert height > 100
    colours = {
        tuple(image.get_at((x, y)))[:3] for x in range(0, width, 7) for y in range(0, height, 7)
    }
    assert len(colours) > 4  # walls, open cells and the ambiguity colours, not a blank page


def test_generate_writes_the_same_bytes_twice(tmp_path: Path) -> None:
    # the second into a folder not made yet, as docs/mazes.md's `-o mazes/m7.toml`
    first, second = tmp_path / "a.toml", tmp_path / "mazes" / "b.toml"
    for path in (first, second):
        code, text = invoke("generate", "--seed", "7", "--ambiguity", "0.2,0.6", "-o", path)
        assert code == 0, text
        assert f'maze = "{path}"' in text
    assert first.read_bytes() == second.read_bytes()
    maze = read_maze(first)
    assert (maze.rows, maze.cols) == (4, 8)
    code, _ = invoke("generate", "--seed", "8", "--ambiguity", "0.2,0.6", "-o", tmp_path / "c.toml")
    assert code == 0
    assert (tmp_path / "c.toml").read_bytes() != first.read_bytes()


def test_show_converts_toml_to_a_picture_and_back(tmp_path: Path) -> None:
    toml, text_file, again = tmp_path / "m.toml", tmp_path / "m.txt", tmp_path / "again.toml"
    assert invoke("generate", "--seed", "3", "-o", toml)[0] == 0
    assert invoke("show", toml, "-o", text_file)[0] == 0
    assert invoke("show", text_file, "-o", again)[0] == 0
    assert read_maze(toml) == read_maze(again)


@pytest.mark.parametrize(
    ("picture", "expected"),
    [
        ("LL..#1#2\nLL#.x...\n", "bad.txt:2: column 5"),
        ("LL..#1#2\nLL#..\n", "bad.txt:2"),
    ],
    ids=["unknown-character", "ragged-row"],
)
def test_a_broken_file_is_refused_in_one_line(tmp_path: Path, picture: str, expected: str) -> None:
    bad = tmp_path / "bad.txt"
    bad.write_text(picture)
    code, text = invoke("show", bad)
    assert code == 1
    lines = [line for line in text.splitlines() if line.strip()]
    assert len(lines) == 1, text
    assert expected in lines[0]
    assert "Traceback" not in text


def test_knobs_out_of_range_are_refused_in_one_line() -> None:
    code, text = invoke("generate", "--ambiguity", "0.8,0.2")
    assert code == 1
    assert len(text.strip().splitlines()) == 1, text
    assert "ambiguity" in text
