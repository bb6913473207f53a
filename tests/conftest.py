"""Test setup: no window ever opens (SDL dummy drivers); a fixture keeping a CPU busy."""

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture
def busy_cpu() -> Iterator[None]:
    """Another process keeping a CPU busy while the test runs (runs must not notice)."""
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    yield
    hog.kill()
    hog.wait()
