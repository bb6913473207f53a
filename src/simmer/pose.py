"""Poses and 2-D vectors: plain named tuples, importable without NumPy or Numba.

:mod:`simmer.geometry` (the compiled kernels) re-exports them; the event stream, recordings
and anything a light command imports take them from here, so that reading an event does not
load a compiler.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["Pose", "Vec2"]


class Vec2(NamedTuple):
    """An immutable 2-D point or vector in inches."""

    x: float
    y: float


class Pose(NamedTuple):
    """An immutable robot pose: position in inches, heading in degrees (BEHAVIOUR §1)."""

    x: float
    y: float
    heading: float
