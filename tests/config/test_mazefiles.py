"""Maze files (issue 34, docs/mazes.md): TOML and text pictures, both ways; the course's maze
by name; a configuration's ``maze``; broken and hostile files refused in one line with the
line and column; a maze file is data and never runs code."""

from __future__ import annotations

from pathlib import Path

import pytest

from simmer.config import config_from_dict, load_config
from simmer.config.mazegen import generate
from simmer.config.mazes import (
    MAX_MAZE_FILE_BYTES,
    MazeSpec,
    course_maze,
    from_walls,
    read_maze,
    read_text,
    read_toml,
    write_maze,
    write_text,
    write_toml,
)
from simmer.config.models import MAX_CELLS_PER_SIDE, SIMMER_DEFAULT_WALLS
from simmer.config.overrides import with_overrides
from simmer.config.project import GenerateSettings
from simmer.config.zones import Zones
from simmer.errors import ConfigError

from helpers import EXAMPLES, PROJECT, default_data

PRACTICE = """\
; a practice maze
name = practice
cell = 12
floor_seed = 7
zone 2 = D9
LL.#1
LL...
#S#.2
"""


def one_line(exc: pytest.ExceptionInfo[ConfigError]) -> str:
    text = str(exc.value)
    assert "\n" not in text
    assert "Traceback" not in text
    return text


def test_course_maze_is_the_default_walls_with_the_project_zones() -> None:
    maze = course_maze("mie444")
    assert maze.walls() == SIMMER_DEFAULT_WALLS
    assert maze == from_walls(SIMMER_DEFAULT_WALLS, "mie444")
    assert maze.dropoff == {"B1": ((0, 5),), "B2": ((0, 7),), "B3": ((2, 2),), "B4": ((3, 7),)}
    assert maze.loading == ((0, 0), (0, 1), (1, 0), (1, 1))


def test_round_trips_toml_text_and_walls() -> None:
    picture = read_text(PRACTICE, "practice.txt")
    assert picture.dropoff == {"B1": ((0, 4),), "D9": ((2, 4),)}
    assert picture.start == ((2, 1),)
    assert picture.floor_seed == 7
    assert read_toml(write_toml(picture)) == picture
    assert read_text(write_text(picture)) == picture
    assert read_text(write_text(read_toml(write_toml(picture)))) == picture
    again = read_toml(write_toml(course_maze("mie444")))
    assert from_walls(again.walls(), "mie444") == again  # walls matrix -> the same zones


def test_every_generated_maze_round_trips() -> None:
    from simmer.config.mazegen import generate
    from simmer.config.project import GenerateSettings

    for seed in range(30):
        maze = generate(GenerateSettings(seed=seed)).maze
        assert read_text(write_text(maze)) == maze
        assert read_toml(write_toml(maze)) == maze


def test_files_by_suffix(tmp_path: Path) -> None:
    maze = read_text(PRACTICE)
    for name in ("p.txt", "p.maze", "p.toml"):
        write_maze(maze, tmp_path / name, comment="made by a test")
        assert read_maze(tmp_path / name) == maze
    assert (tmp_path / "p.txt").read_text().startswith("; made by a test")


@pytest.mark.parametrize(
    ("text", "where"),
    [
        ("LL..\nLL.\n", ":2: column 4: this row has 3 cells but the first has 4"),
        ("LL..\nLLx.\n", ":2: column 3: unknown character 'x'"),
        ("cell = -1\nLL..\n", ":1: column 8: cell must be a number of inches above 0"),
        ("LL..\nLL..\nwho = 1\n", ":3: column 1: a setting after the picture's rows"),
        ("depth = 3\nLL..\n", ":1: column 1: unknown setting 'depth'"),
        ("L.#.\n..#.\n", ":1: column 4: open cell [0, 3] (and 1 more) cannot be reached"),
        ("; nothing\n", "has no picture"),
    ],
)
def test_broken_pictures_say_line_and_column(text: str, where: str) -> None:
    with pytest.raises(ConfigError) as exc:
        read_text(text, "m.txt")
    assert where in one_line(exc)


@pytest.mark.parametrize(
    ("text", "where"),
    [
        ("walls = [\n  [1, 1],\n  [1, 1, 1],\n]\n", "m.toml:3: column 3: walls[1] has 3 cells"),
        ("walls = [[1, 1], [1, 0]]\n[zones]\nloading = [[1, 1]]\n", "loading zone is on a solid"),
        ("walls = [[1, 1]]\n[zones]\nstart = [[0, 9]]\n", "cell [0, 9] is outside the maze"),
        ("walls = [[1, 1]]\ncolour = 3\n", "m.toml:2: column 1: unknown key 'colour'"),
        ("walls = [[1, 'a']]\n", "walls[0][1] is 'a'"),
        ("walls = [[1, 1]\n", "m.toml:1: not valid TOML"),
        ("walls = [[1, 1]]\nfloor_seed = -4\n", "m.toml:2: floor_seed must be a whole number"),
    ],
)  # fmt: skip
def test_broken_toml_says_line_and_column(text: str, where: str) -> None:
    with pytest.raises(ConfigError) as exc:
        read_toml(text, "m.toml")
    assert where in one_line(exc)


def test_a_maze_over_the_cap_is_refused_before_it_is_built() -> None:
    row = "." * (MAX_CELLS_PER_SIDE + 1)
    with pytest.raises(ConfigError) as exc:
        read_text(row + "\n")
    assert "MAX_CELLS_PER_SIDE" in one_line(exc)
    assert "column 501" in one_line(exc)
    tall = ".\n" * (MAX_CELLS_PER_SIDE + 1)
    with pytest.raises(ConfigError) as exc:
        read_text(tall)
    assert f":{MAX_CELLS_PER_SIDE + 1}: " in one_line(exc)
    with pytest.raises(ConfigError) as exc:
        read_toml("walls = [" + "[1]," * (MAX_CELLS_PER_SIDE + 1) + "]")
    assert "MAX_CELLS_PER_SIDE" in one_line(exc)


def test_a_huge_file_is_refused_unread(tmp_path: Path) -> None:
    huge = tmp_path / "huge.txt"
    with huge.open("wb") as f:
        f.truncate(MAX_MAZE_FILE_BYTES + 1)  # sparse: nothing to read
    with pytest.raises(ConfigError) as exc:
        read_maze(huge)
    assert "MAX_MAZE_FILE_BYTES" in one_line(exc)
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\xff\xfe\x00walls")
    with pytest.raises(ConfigError) as exc:
        read_maze(binary)
    assert "UTF-8" in one_line(exc)
    with pytest.raises(ConfigError) as exc:
        read_maze(tmp_path)
    assert "not a regular file" in one_line(exc)


def test_a_maze_file_is_data_and_never_runs_code(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    code = f"import pathlib; pathlib.Path({str(marker)!r}).write_text('x')"
    quoted = tmp_path / "quoted.toml"
    quoted.write_text(f'walls = [[1, 1]]\nname = "{code}"\n')
    assert read_maze(quoted).name == code  # text, kept as text
    for name, text in [
        ("evil.txt", f"{code}\n..\n"),
        ("evil.toml", f"__import__('os').system('touch {marker}')\n"),
        ("evil.py", f"{code}\nwalls = [[1, 1]]\n"),
    ]:
        path = tmp_path / name
        path.write_text(text)
        with pytest.raises(ConfigError) as exc:
            read_maze(path)
        one_line(exc)
    assert not marker.exists()


def test_configuration_names_a_maze_file(tmp_path: Path) -> None:
    (tmp_path / "mazes").mkdir()
    write_maze(read_text(PRACTICE), tmp_path / "mazes" / "practice.txt")
    data = default_data()
    data["maze"] = "mazes/practice.txt"
    config = config_from_dict(data, "robot.toml", tmp_path)
    s = config.settings
    assert s.walls == read_text(PRACTICE).walls()
    assert s.floor_seed == 7
    zones = Zones.from_settings(s)
    assert set(zones.dropoff) == {"B1", "D9"}
    assert zones.start == ((2, 1),)
    assert s.robot_start_position == (18.0, 30.0)  # the start cell's centre
    data["maze"] = "mazes/missing.toml"
    with pytest.raises(ConfigError) as exc:
        config_from_dict(data, "robot.toml", tmp_path)
    assert "robot.toml: maze: " in one_line(exc)
    assert "no such maze file" in one_line(exc)


def test_a_broken_maze_file_is_named_through_the_configuration(tmp_path: Path) -> None:
    (tmp_path / "bad.txt").write_text("LL..\nLL?.\n")
    config = tmp_path / "robot.toml"
    config.write_text('maze = "bad.txt"\n' + (EXAMPLES / "lab1_rover.toml").read_text())
    with pytest.raises(ConfigError) as exc:
        load_config(config)
    assert f"robot.toml:1: maze: {tmp_path / 'bad.txt'}:2: column 3: unknown character" in str(
        exc.value
    )


def test_course_maze_by_name_and_inline_walls_keep_working() -> None:
    data = default_data()
    data["maze"] = "mie444"
    by_name = config_from_dict(data, "x", Path.cwd()).settings
    inline = config_from_dict(default_data(), "x", Path.cwd()).settings
    assert by_name.walls == inline.walls
    assert load_config(PROJECT).settings.walls == SIMMER_DEFAULT_WALLS


def test_maze_and_walls_together_are_refused(tmp_path: Path) -> None:
    config = tmp_path / "robot.toml"
    config.write_text('maze = "mie444"\nwalls = [[1, 1]]\n')
    with pytest.raises(ConfigError) as exc:
        load_config(config)
    assert "robot.toml:2: walls: sets both maze and walls" in one_line(exc)


def test_overriding_the_maze_seed_makes_another_maze() -> None:
    data = default_data()
    data["maze"] = {"seed": 1}
    config = config_from_dict(data, "x", Path.cwd())
    walls = {with_overrides(config, {"maze.seed": seed}).settings.walls for seed in range(6)}
    assert len(walls) == 6
    assert with_overrides(config, {"maze.seed": 1}).settings.walls == config.settings.walls
    named = with_overrides(config, {"maze": "mie444"}).settings
    assert named.walls == SIMMER_DEFAULT_WALLS


def test_a_bad_generator_table_names_its_key() -> None:
    data = default_data()
    data["maze"] = {"seed": 1, "loops": [0.5, 0.2]}
    with pytest.raises(ConfigError) as exc:
        config_from_dict(data, "x", Path.cwd())
    assert "maze" in str(exc.value)
    assert "loops must be [least, most]" in str(exc.value)


def test_spec_is_plain_data() -> None:
    maze = MazeSpec(((True, True),))
    assert maze.start_cells() == ((0, 0), (0, 1))
    assert maze.walls() == ((1, 1),)


def test_a_maze_override_replaces_a_configuration_without_one() -> None:
    project = load_config(PROJECT)  # no maze: its walls, start and block are the built-in ones
    assert project.settings.maze is None
    seeded = with_overrides(project, {"maze.seed": 5}).settings
    made = generate(GenerateSettings(seed=5)).maze
    assert seeded.walls == made.walls()
    assert list(seeded.robot_start_position) == made.places()["robot_start_position"]
    assert seeded.robot_outline == project.settings.robot_outline  # the file's own settings stay
    named = with_overrides(project, {"maze": "mie444"}).settings
    assert named.walls == SIMMER_DEFAULT_WALLS


def test_robot_maze_names_the_maze_a_program_can_build_again() -> None:
    from simmer.localize.mapdata import map_data
    from simmer.world import Simulation

    project = load_config(PROJECT)
    assert map_data(Simulation(project))["maze"] is None
    seeded = with_overrides(project, {"maze.seed": 9})
    named = map_data(Simulation(seeded))["maze"]
    assert named["seed"] == 9
    again = with_overrides(project, {"maze": named}).settings
    assert again.walls == seeded.settings.walls


def test_a_start_pose_round_trips_and_a_bad_one_is_refused_with_its_line() -> None:
    from dataclasses import replace

    posed = replace(course_maze("mie444"), start_pose=(42.0, 42.0, 90.0))
    assert read_text(write_text(posed)) == posed
    assert read_toml(write_toml(posed)) == posed
    data = posed.settings_data()
    assert (data["robot_start_position"], data["robot_start_rotation"]) == ([42.0, 42.0], 90.0)
    picture = write_text(posed)
    for bad, message in (
        ("start = 18.0, 30.0, 90.0", "p.txt:9: column 2: the start pose is on a solid cell"),
        ("start = 42, 42", "p.txt:6: column 9: the start pose is x, y, heading"),
        ("start = 999.0, 1.0, 0.0", "is not inside the maze"),
    ):
        with pytest.raises(ConfigError) as exc:
            read_text(picture.replace("start = 42.0, 42.0, 90.0", bad), "p.txt")
        assert message in one_line(exc), one_line(exc)
    toml = write_toml(posed).replace("robot_start_rotation = 90.0", 'robot_start_rotation = "x"')
    with pytest.raises(ConfigError) as exc:
        read_toml(toml, "p.toml")
    assert "p.toml:" in one_line(exc)
    assert "the start pose is x, y, heading" in one_line(exc)
