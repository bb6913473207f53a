"""The project's zones: the ``project`` and ``lab2023`` conventions, zones named outright, and bad
zones named plainly."""

from __future__ import annotations

from typing import Any

import pytest

from simmer.config.zones import Zones
from simmer.errors import ConfigError

from helpers import make_config, project_data


def test_project_convention_zones_of_the_default_maze() -> None:
    zones = Zones.from_settings(make_config(project_data()).settings)
    assert zones.loading is not None
    assert zones.loading.cells == ((0, 0), (0, 1), (1, 0), (1, 1))
    assert {name: z.cells for name, z in zones.dropoff.items()} == {
        "B1": ((0, 5),),
        "B2": ((0, 7),),
        "B3": ((2, 2),),
        "B4": ((3, 7),),
    }
    assert (3, 0) in zones.start
    assert (0, 0) not in zones.start
    assert (0, 5) not in zones.start


def test_lab2023_convention_and_named_zones() -> None:
    data = project_data()
    data["zones"] = {"convention": "lab2023"}
    zones = Zones.from_settings(make_config(data).settings)
    assert zones.loading is not None
    assert zones.loading.cells == ((0, 5), (0, 7), (2, 2), (3, 7))
    assert list(zones.dropoff) == ["D1"]
    assert zones.start == ((0, 0), (0, 1), (1, 0), (1, 1))
    data["zones"] = {"loading": [[3, 0]], "dropoff": {"HOME": [[3, 1], [3, 2]]}}
    data["scenario"]["target"] = "HOME"
    zones = Zones.from_settings(make_config(data).settings)
    assert zones.loading is not None
    assert zones.loading.cells == ((3, 0),)
    assert zones.dropoff["HOME"].contains(30.0, 40.0, 12.0)


@pytest.mark.parametrize(
    ("zones", "key", "words"),
    [
        ({"loading": [[9, 0]]}, "zones.loading[0]", "outside the maze"),
        ({"dropoff": {"B1": [[0, 4]]}}, "zones.dropoff.B1[0]", "is solid"),
        ({"dropoff": {"B-1": [[0, 5]]}}, "zones.dropoff", "letters or digits"),
        ({"convention": "2025"}, "zones.convention", "project"),
    ],
)
def test_bad_zones_are_named_plainly(zones: dict[str, Any], key: str, words: str) -> None:
    data = project_data()
    data["zones"] = zones
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    text = str(caught.value)
    assert key in text
    assert words in text
