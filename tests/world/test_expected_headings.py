"""A table's headings are checked before any arithmetic: any three floats give an array of at
most MAX_HEADINGS finite headings or a ValueError saying why (``-1e308:1e308:1e307`` was an
OverflowError)."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from simmer.world.expected import MAX_HEADINGS, parse_headings

FLOATS = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)


@given(start=FLOATS, stop=FLOATS, step=FLOATS)
def test_any_headings_give_an_array_or_a_value_error(
    start: float, stop: float, step: float
) -> None:
    try:
        angles = parse_headings(f"{start!r}:{stop!r}:{step!r}")
    except ValueError:  # said plainly; an OverflowError would fail the test
        return
    assert 0 < len(angles) <= MAX_HEADINGS
    assert all(map(math.isfinite, angles))
