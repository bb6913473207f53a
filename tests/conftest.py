"""Test setup: no window ever opens (SDL dummy drivers); the slow tests go first; the same
generated examples on every run; a fixture keeping a CPU busy."""

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import settings

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
sys.path.insert(0, str(Path(__file__).parent))

settings.register_profile("repeatable", derandomize=True, database=None)
"""The suite's generated tests (fuzzing, properties) draw the same examples on every run, so
a run passes or fails the same way on any machine; ``--hypothesis-profile explore`` draws new
ones each time, to look for what these miss."""
settings.register_profile("explore", derandomize=False)
settings.load_profile("repeatable")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The ``fresh`` and ``slow`` tests first (in their order; the rest after, in theirs): the
    suite is spread over every CPU (``-n auto``, two tests at a time to each worker as it frees
    up: ``--maxschedchunk 2`` in pyproject.toml), and a test of seconds started last would keep
    one CPU busy after the others are done."""

    def order(item: pytest.Item) -> int:
        if item.get_closest_marker("fresh") is not None:
            return 0
        return 1 if item.get_closest_marker("slow") is not None else 2

    items.sort(key=order)


@pytest.fixture
def busy_cpu() -> Iterator[None]:
    """Another process keeping a CPU busy while the test runs (runs must not notice)."""
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    yield
    hog.kill()
    hog.wait()
