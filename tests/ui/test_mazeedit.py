"""The maze editor (``simmer maze edit``, issue 34) driven through pygame's event queue under
the dummy video driver: clicks cycle cells, a drag moves the start pose, S saves a valid maze
and refuses an invalid one saying why."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pygame
import pytest

from simmer.config.mazes import course_maze, read_maze, write_maze
from simmer.ui.mazeedit import MazeEditor, window_size

from helpers import let_time_pass


@pytest.fixture
def editor(tmp_path: Path) -> MazeEditor:
    pygame.display.init()
    pygame.font.init()
    path = tmp_path / "practice.txt"
    maze = course_maze("mie444")
    write_maze(maze, path)
    pygame.event.clear()
    return MazeEditor(path, read_maze(path), pygame.Surface(window_size(maze)))


def click(ed: MazeEditor, pos: tuple[int, int]) -> None:
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=pos, button=1))
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=pos, button=1))
    assert ed.frame()


def press(ed: MazeEditor, key: int) -> bool:
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=key, unicode="", mod=0))
    return ed.frame()


def test_clicks_cycle_a_cell_and_s_saves_the_maze(editor: MazeEditor) -> None:
    assert editor.chars[0][4] == "#"
    click(editor, editor.cell_centre(0, 4))
    assert editor.chars[0][4] == "."
    assert press(editor, pygame.K_s)
    assert editor.status == f"saved {editor.path}"
    saved = read_maze(editor.path)
    assert saved.open[0][4]
    assert sum(map(sum, saved.open)) == sum(map(sum, course_maze("mie444").open)) + 1
    for expected in ("S", "L", "5"):  # start cell, loading zone, the first free digit (B5)
        click(editor, editor.cell_centre(0, 4))
        assert editor.chars[0][4] == expected
    click(editor, editor.cell_centre(0, 4))
    assert editor.chars[0][4] == "#"


def test_dragging_the_robot_moves_the_start_pose_and_r_turns_it(editor: MazeEditor) -> None:
    before = tuple(editor.pose)
    grab = tuple(round(v) for v in editor.to_pixel(editor.pose[0], editor.pose[1]))
    drop = editor.cell_centre(3, 3)
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=grab, button=1))
    pygame.event.post(
        pygame.event.Event(pygame.MOUSEMOTION, pos=drop, rel=(0, 0), buttons=(1, 0, 0))
    )
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=drop, button=1))
    assert editor.frame()
    assert editor.pose[:2] == [42.0, 42.0]  # the centre of cell [3, 3]
    assert editor.chars == [list(r) for r in ("LL..#1#2", "LL#.....", ".#3##.#.", "......#4")]
    press(editor, pygame.K_r)
    assert press(editor, pygame.K_s)
    saved = read_maze(editor.path)
    assert saved.start_pose == (42.0, 42.0, (before[2] + 90.0) % 360.0)
    assert saved.settings_data()["robot_start_position"] == [42.0, 42.0]


def test_an_invalid_maze_is_not_saved_and_the_window_says_why(editor: MazeEditor) -> None:
    before = editor.path.read_bytes()
    click(editor, editor.cell_centre(3, 0))  # open -> start cell
    click(editor, editor.cell_centre(3, 1))
    for _ in range(4):  # [2, 0] open -> S -> L -> digit -> solid: [3, 0]'s only way out
        click(editor, editor.cell_centre(2, 0))
    for _ in range(3):  # [3, 1] S -> L -> digit -> solid
        click(editor, editor.cell_centre(3, 1))
    assert editor.chars[2][0] == "#"
    assert editor.chars[3][1] == "#"
    assert press(editor, pygame.K_s)
    assert editor.status.startswith("not saved: practice.txt:")
    assert "cannot be reached" in editor.status
    assert editor.path.read_bytes() == before
    assert not editor.saved


def test_the_ambiguity_map_is_drawn_and_a_toggles_it(editor: MazeEditor) -> None:
    editor.draw()
    x, y = editor.cell_centre(0, 3)
    shown = editor.surface.get_at((x - 8, y - 8))[:3]
    assert shown != (250, 250, 250)  # tinted by its count
    assert editor.alike()[0, 3] >= 0
    press(editor, pygame.K_a)
    assert editor.surface.get_at((x - 8, y - 8))[:3] == (250, 250, 250)


def test_escape_closes_the_editor(editor: MazeEditor) -> None:
    assert not press(editor, pygame.K_ESCAPE)


@pytest.mark.slow  # starts simmer three times
@pytest.mark.usefixtures("ctrl_c")
@pytest.mark.parametrize("after", [0.0, 0.05, 0.3])
def test_ctrl_c_in_the_terminal_ends_the_editor_as_closing_it(tmp_path: Path, after: float) -> None:
    """Ctrl-C at once after the editor says it is editing (pygame still starting), or later in
    its loop: it ends, saying the maze was not saved, with no traceback."""
    env = os.environ | {"SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    process = subprocess.Popen(
        [sys.executable, "-m", "simmer", "maze", "edit", "practice.txt"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    assert process.stdout is not None
    first = process.stdout.readline()
    assert first.startswith("editing practice.txt"), first
    let_time_pass(after)  # the moment Ctrl-C lands, not a wait for something to happen
    process.send_signal(signal.SIGINT)
    rest, _ = process.communicate(timeout=60)
    assert process.returncode == 0, rest
    assert rest.strip().splitlines()[-1] == "practice.txt not saved", rest
    assert "Traceback" not in rest
