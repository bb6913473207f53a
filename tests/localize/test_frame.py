"""The coordinate frame the map states (``robot.maze()``'s ``units`` and ``frame``) is the one
the simulation moves in, and the same words as the docs' Coordinates section."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from simmer.localize.mapdata import FRAME, map_data

from helpers import REPO, default_data, make_sim


@pytest.mark.parametrize("heading", [0.0, 90.0, 180.0, 270.0, 30.0])
def test_a_move_goes_where_the_frame_says(heading: float) -> None:
    data = default_data()
    data["robot_start_position"] = [30.0, 30.0]
    data["walls"] = [[1] * 8 for _ in range(4)]  # an open floor: nothing stops the move
    data["robot_start_rotation"] = heading
    sim = make_sim(data)
    sim.command("w0-6")
    sim.run_until_idle()
    rad = math.radians(heading)
    assert sim.robot.pose.x - 30.0 == pytest.approx(-6 * math.sin(rad), abs=1e-9)
    assert sim.robot.pose.y - 30.0 == pytest.approx(6 * math.cos(rad), abs=1e-9)


def test_a_positive_turn_grows_the_heading() -> None:
    sim = make_sim()
    start = sim.robot.pose.heading
    sim.command("r0-90")
    sim.run_until_idle()
    assert sim.robot.pose.heading == pytest.approx((start + 90) % 360)


def test_the_map_states_the_frame_in_the_docs_words() -> None:
    maze = map_data(make_sim())
    assert maze["frame"] == dict(FRAME)
    assert "clockwise" in maze["units"]
    assert "counter-clockwise from +y" not in maze["units"]
    readme = " ".join((REPO / "README.md").read_text(encoding="utf-8").split())
    for words in (
        "0 faces +y (down the window), 90 faces -x (left)",
        "dx = -d·sin h, dy = d·cos h",
    ):
        assert words in readme
    for page in ("lab1.md", "project.md", "localization.md"):
        text = " ".join(Path(REPO / "docs" / page).read_text(encoding="utf-8").split())
        assert "0 faces +y (down the window), 90 faces -x (left), 180 faces -y (up)" in text, page
        assert "counter-clockwise from +y" not in text, page
