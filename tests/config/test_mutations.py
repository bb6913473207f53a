"""A few hundred mutated configurations (issue 9): each is either refused with clean issues, one
line each naming a key, or it runs: its simulation builds, steps, answers ``u0,w0-1`` and is
drawn, without an exception.

The mutations start from the built-in default and ``examples/lab1_rover.toml`` and are drawn
with a fixed seed from every way of breaking a key: removing it, emptying a table, wrapping a
value in lists, shortening, lengthening or repeating a list a thousand times, giving NaN,
infinity, huge, tiny, negative or zero numbers, text for a number, a truth value for a number,
and the wrong type. Settings and device settings that the files do
not write are mutated too.
"""

from __future__ import annotations

import copy
import math
import random
import tomllib
from collections.abc import Callable, Iterator
from typing import Any

import pygame
import pytest

from simmer import Simulation
from simmer.config import Settings, SimConfig, config_from_dict
from simmer.config.models import MAX_DRAWING_PIXELS
from simmer.devices import get_device_kind
from simmer.errors import ConfigError
from simmer.ui.render import PygameRenderer
from simmer.ui.scene import PANEL_HEIGHT, ScenePainter, View, default_window_size
from simmer.view.snapshot import Snapshot, StaticScene

from helpers import EXAMPLES, REPO, default_data

pytestmark = pytest.mark.timeout(30)

Data = dict[str, Any]
Path_ = tuple[str | int, ...]
Mutation = Callable[[Data], None]

SOURCES: dict[str, Data] = {
    "default": default_data(),
    "lab1": tomllib.loads((EXAMPLES / "lab1_rover.toml").read_text(encoding="utf-8")),
}
ODD_VALUES: list[Any] = [
    math.nan, math.inf, -math.inf, 1e308, -1e308, 1e-308, 1e6, 1e-6, 0, -1, -1e6, 2**63 - 1,
    True, "12", "abc", "", [], {}, None, [[[[1]]]],
]  # fmt: skip
COUNT = 600
"""Mutations drawn (of some 8,000, which all pass); each takes about 1 ms refused, 5 ms run."""


def paths(value: Any, path: Path_ = ()) -> Iterator[Path_]:
    """Every key and list position inside ``value``, outermost first."""
    items = value.items() if isinstance(value, dict) else enumerate(value)
    for key, inner in items:
        yield (*path, key)
        if isinstance(inner, dict | list):
            yield from paths(inner, (*path, key))


def unwritten_keys(data: Data) -> Iterator[Path_]:
    """Settings and device settings ``data`` leaves at their defaults."""
    yield from ((name,) for name in Settings.model_fields if name not in data)
    for group in ("motors", "drives", "sensors"):
        for device_id, table in data.get(group, {}).items():
            kind = get_device_kind(table.get("type", group[:-1]))
            assert kind is not None
            for name in kind.Params.model_fields:
                if name not in table:
                    yield (group, device_id, name)


def parent_of(data: Data, path: Path_) -> Any:
    target: Any = data
    for part in path[:-1]:
        target = target[part]
    return target


def set_to(path: Path_, value: Any) -> Mutation:
    def mutate(data: Data) -> None:
        parent_of(data, path)[path[-1]] = copy.deepcopy(value)

    return mutate


def removed(path: Path_) -> Mutation:
    def mutate(data: Data) -> None:
        del parent_of(data, path)[path[-1]]

    return mutate


def wrapped(path: Path_, depth: int) -> Mutation:
    def mutate(data: Data) -> None:
        parent = parent_of(data, path)
        for _ in range(depth):
            parent[path[-1]] = [parent[path[-1]]]

    return mutate


def mutations(name: str, data: Data) -> Iterator[tuple[str, Mutation]]:
    """Every mutation of one source, each with a readable id."""
    written = list(paths(data))
    for path in written:
        key = ".".join(map(str, path))
        if isinstance(path[-1], str):
            yield f"{name}:{key} removed", removed(path)
        value = parent_of(data, path)[path[-1]]
        if isinstance(value, dict):
            yield f"{name}:{key} = {{}}", set_to(path, {})
        if isinstance(value, list) and value:
            yield f"{name}:{key} shortened", set_to(path, value[:-1])
            yield f"{name}:{key} lengthened", set_to(path, [*value, value[-1]])
            yield f"{name}:{key} repeated 1000 times", set_to(path, value * 1000)
        for depth in (1, 2):
            yield f"{name}:{key} nested {depth}", wrapped(path, depth)
    for path in [*written, *unwritten_keys(data)]:
        key = ".".join(map(str, path))
        for odd in ODD_VALUES:
            yield f"{name}:{key} = {odd!r}", set_to(path, odd)


def drawn_mutations() -> list[tuple[str, str, Mutation]]:
    """COUNT mutations, the same every run."""
    every = [
        (source, label, mutate)
        for source, data in SOURCES.items()
        for label, mutate in mutations(source, data)
    ]
    return random.Random(444).sample(every, COUNT)


def runs(config: SimConfig) -> None:
    """Build, step, command and draw a simulation of ``config``; any exception fails."""
    sim = Simulation(config, seed=1)
    sim.step(3)
    assert len(sim.command("u0,w0-1")) == 2
    sim.step(3)
    size = default_window_size(sim)
    assert max(size) <= MAX_DRAWING_PIXELS + PANEL_HEIGHT, size
    painter = ScenePainter(StaticScene.of(sim))
    renderer = PygameRenderer(pygame.Surface((64, 64)))  # clipped: the numbers are what count
    view = View.fit(sim, size)
    painter.paint_static(renderer, view, size)
    painter.paint_dynamic(renderer, view, Snapshot.of(sim))


LIBRARY_WORDING = ("Input should", "Value error", "pydantic", "np.float64", "Traceback")


def validated(source: str, mutate: Mutation) -> SimConfig | ConfigError:
    """The mutated source's configuration, or the error refusing it."""
    data = copy.deepcopy(SOURCES[source])
    mutate(data)
    try:
        return config_from_dict(data, "mutated.toml", REPO)
    except ConfigError as exc:
        return exc


@pytest.mark.parametrize(
    ("source", "mutate"), [pytest.param(s, m, id=label) for s, label, m in drawn_mutations()]
)
def test_mutated_configuration_is_refused_cleanly_or_runs(source: str, mutate: Mutation) -> None:
    result = validated(source, mutate)
    if isinstance(result, SimConfig):
        runs(result)
        return
    assert result.issues
    for issue in result.issues:
        line = issue.render(result.source)
        assert issue.key, line
        assert line.isprintable(), line  # one line: no line break, no control character
        assert not any(word in line for word in LIBRARY_WORDING), line


@pytest.mark.slow
def test_the_mutations_both_refuse_and_run() -> None:
    """The drawn sample holds both outcomes (so neither check above is vacuous)."""
    results = [validated(source, mutate) for source, _, mutate in drawn_mutations()]
    refused = sum(isinstance(result, ConfigError) for result in results)
    assert refused >= COUNT // 4
    assert len(results) - refused >= COUNT // 10
