"""Sweeps over mazes (issue 34, docs/mazes.md): ``maze.seed`` (sampled) and ``maze`` (files,
gridded) through a real ``simmer sweep``, each maze drawn as a thumbnail coloured by success,
and the course project's scenario (random start, block and target) in every generated maze."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import numpy as np
import pygame
import pytest

from simmer import Simulation, load_config
from simmer.config import with_overrides
from simmer.config.maze import Maze
from simmer.config.mazes import read_maze
from simmer.config.scenario import robot_fits

from helpers import EXAMPLES, REPO, run_simmer

POLICIES = REPO / "tests" / "fixtures" / "sweep" / "sweep_policies.py"
PROJECT = EXAMPLES / "project.toml"


def read_table(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as file:
        return list(csv.DictReader(file))


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_a_sweep_over_generated_mazes_and_maze_files_draws_each_maze(tmp_path: Path) -> None:
    shutil.copy(POLICIES, tmp_path)
    shutil.copy(PROJECT, tmp_path / "project.toml")
    mazes = tmp_path / "mazes"
    mazes.mkdir()
    for seed, name in ((11, "a.toml"), (12, "b.txt")):
        made = run_simmer("maze", "generate", "--seed", seed, "-o", mazes / name)
        assert made.returncode == 0, made.stderr
    (tmp_path / "seeds.toml").write_text(
        'config = "project.toml"\npolicy = "sweep_policies:drive_and_stop"\nseeds = 2\n'
        'keep = "nothing"\nsuccess = "path_length >= 0"\n'
        '[grid]\n"scenario.start" = ["random"]\n'
        '[sample]\ncount = 3\n"maze.seed" = {choice = [1, 2, 3, 4, 5, 6, 7, 8]}\n',
        encoding="utf-8",
    )
    (tmp_path / "files.toml").write_text(
        'config = "project.toml"\npolicy = "sweep_policies:drive_and_stop"\nseeds = 1\n'
        'keep = "nothing"\nsuccess = "path_length < 0"\n'
        '[grid]\nmaze = ["mazes/a.toml", "mazes/b.txt", "mie444"]\n',
        encoding="utf-8",
    )
    for name, column, succeeded in (("seeds", "maze.seed", True), ("files", "maze", False)):
        out = tmp_path / f"{name}-out"
        done = run_simmer("sweep", tmp_path / f"{name}.toml", "-o", out, "--workers", "1")
        assert done.returncode == 0, done.stdout + done.stderr
        rows = read_table(out / "results.csv")
        assert {row["status"] for row in rows} == {"ok"}, rows
        assert len({row[column] for row in rows}) > 1
        assert {row["success"] for row in rows} == {str(succeeded)}
        starts = {row[column]: (row["start_x"], row["start_y"]) for row in rows}
        assert len(set(starts.values())) > 1  # each maze draws its start in its own cells
        assert "mazes.png" in (out / "summary.md").read_text(encoding="utf-8")
        picture = pygame.image.load(str(out / "mazes.png"))
        r, g, b = pygame.surfarray.array3d(picture).reshape(-1, 3).astype(int).T
        green = ((g > r + 40) & (g > b + 15)).sum()
        red = ((r > g + 40) & (r > b + 40)).sum()
        coloured, other = (green, red) if succeeded else (red, green)
        assert coloured > 1000, "the mazes are not coloured by their runs' success"
        assert other < coloured / 20
    # the maze a run had is the maze it was swept over: rerun one seed's maze alone
    project = load_config(tmp_path / "project.toml")
    for row in read_table(tmp_path / "seeds-out" / "results.csv"):
        settings = with_overrides(project, {"maze.seed": int(row["maze.seed"])}).settings
        opened = np.array(settings.walls) != 0
        cell = (int(float(row["start_y"]) // 12), int(float(row["start_x"]) // 12))
        assert opened[cell]
    by_file = {r["maze"]: r for r in read_table(tmp_path / "files-out" / "results.csv")}
    a = read_maze(mazes / "a.toml")
    x, y = float(by_file["mazes/a.toml"]["start_x"]), float(by_file["mazes/a.toml"]["start_y"])
    assert a.open[int(y // a.cell)][int(x // a.cell)]


@pytest.mark.slow
def test_the_project_scenario_works_in_every_generated_maze() -> None:
    base = load_config(PROJECT)
    for maze_seed in range(300):
        config = with_overrides(
            base, {"maze.seed": maze_seed, "scenario.start": "random", "scenario.target": "random"}
        )
        maze = Maze.from_settings(config.settings)
        for run_seed in range(3):
            sim = Simulation(config, seed=run_seed)
            scenario = sim.scenario
            zones = sim.zones
            assert zones.loading is not None
            assert len(zones.loading.cells) == 4
            assert scenario.target in zones.dropoff
            bx, by = scenario.block
            assert (int(by // maze.cell), int(bx // maze.cell)) in zones.loading.cells
            start = scenario.start
            cell = (int(start.y // maze.cell), int(start.x // maze.cell))
            assert not maze.solid[cell]
            assert cell not in zones.loading.cells
            assert robot_fits(config.settings, maze, start.x, start.y, start.heading)
