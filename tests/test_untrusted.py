"""Text and JSON from outside (issue 28, items 3 and 4): one sanitiser before every font, one
bounded JSON reader."""

from __future__ import annotations

import io
import json
import os
import sys
import warnings
from typing import Any

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import pygame
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from simmer.record.plots import drawable_texts
from simmer.ui.render import TextCache, has_glyph
from simmer.untrusted import (
    CUT,
    MAX_DRAWN_CHARS,
    MAX_JSON_DEPTH,
    REPLACEMENT,
    drawable,
    nests_deeper,
    parse_json,
)

HOSTILE = ["\x00", "\ud800", "\u202e", "\ufeff", "\u200b", "\x1b[2J", "\u2066", "\u00ad"]
"""Each made pygame raise (NUL, a lone surrogate, "Text has zero width") or could reorder,
hide or colour what is drawn."""

ANY_TEXT = st.text(st.characters(exclude_categories=()), max_size=300)
"""Any text at all, lone surrogates included."""


@pytest.mark.parametrize("char", HOSTILE)
def test_each_hostile_character_is_replaced(char: str) -> None:
    shown = drawable(f"a{char}b")
    assert shown == f"a{REPLACEMENT}{char[1:]}b"
    shown.encode("utf-8")  # a lone surrogate could not be


def test_printable_text_is_kept_and_long_text_is_cut() -> None:
    assert drawable("B2 éå 1.5 in") == "B2 éå 1.5 in"
    cut = drawable("x" * 10_000)
    assert len(cut) == MAX_DRAWN_CHARS
    assert cut.endswith(CUT)


def test_a_character_the_font_lacks_is_replaced_only_where_it_is_drawn() -> None:
    assert has_glyph("é")
    assert not has_glyph("中")
    assert drawable("中", has_glyph) == REPLACEMENT
    assert drawable("中") == "中"  # a font that has it may draw it


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(ANY_TEXT)
def test_any_text_is_drawn_by_pygame_and_bounded(text: str) -> None:
    shown = drawable(text, has_glyph)
    assert len(shown) <= MAX_DRAWN_CHARS
    assert all(c == REPLACEMENT or has_glyph(c) for c in shown)
    surface = TextCache().get(text, (255, 255, 255), 18)  # the one place text meets a font
    assert isinstance(surface, pygame.Surface)


@pytest.mark.slow
@settings(max_examples=25, deadline=None)
@given(ANY_TEXT)
def test_any_text_is_drawn_by_matplotlib_without_a_warning(text: str) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 1), dpi=20)
    ax = fig.subplots()
    ax.set_title(text)
    ax.plot([0, 1], [0, 1], label="x" + text + "$\\foo$")
    ax.legend()
    ax.annotate(text, (0.5, 0.5))
    drawable_texts(fig)
    FigureCanvasAgg(fig)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "Glyph missing from font" is a warning
        fig.savefig(io.BytesIO(), format="png")


def test_a_figures_line_breaks_stay_and_each_line_is_cleaned() -> None:
    """Every plot's title has two lines; the sanitiser turned its line break into ``?``."""
    from matplotlib.figure import Figure

    fig = Figure()
    title = fig.subplots().set_title("Path of the run in run\x00\n1.0 s \u202e driven")
    drawable_texts(fig)
    assert title.get_text() == "Path of the run in run?\n1.0 s ? driven"


# ----------------------------------------------------------------------------- JSON


def nested(depth: int) -> Any:
    value: Any = 1
    for level in range(depth):
        value = [value] if level % 2 else {"a": value}
    return value


def true_depth(value: Any) -> int:
    if isinstance(value, list):
        return 1 + max(map(true_depth, value), default=0)
    if isinstance(value, dict):
        return 1 + max(map(true_depth, value.values()), default=0)
    return 0


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.floats(allow_nan=False) | st.text(st.sampled_from('[]{}"\\a')),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=3), inner),
    max_leaves=40,
)


@pytest.mark.slow
@settings(max_examples=100, deadline=None)
@given(JSON_VALUES, st.integers(0, 6))
def test_the_depth_is_counted_as_the_parser_nests(value: Any, limit: int) -> None:
    text = json.dumps(value, ensure_ascii=False)
    assert nests_deeper(text, limit) == (true_depth(value) > limit)


def test_deep_nesting_is_one_plain_error_naming_the_limit() -> None:
    assert parse_json(json.dumps(nested(MAX_JSON_DEPTH)), "x") == nested(MAX_JSON_DEPTH)
    for text in ["[" * 3000, json.dumps(nested(MAX_JSON_DEPTH + 1)), '{"a":' * 100_000]:
        with pytest.raises(ValueError, match=r"^a belief is not readable JSON: .*MAX_JSON_DEPTH"):
            parse_json(text, "a belief")
    assert sys.getrecursionlimit() < 100_000  # what the bound guards against


def test_brackets_inside_strings_are_not_nesting() -> None:
    text = json.dumps({"labels": [[1, 2, "[" * 5000 + '\\"{' * 100]]})
    assert parse_json(text, "x")["labels"][0][2].startswith("[[[")


def test_size_is_bounded_before_parsing() -> None:
    with pytest.raises(ValueError, match=r"is 11 characters, over the limit of 10 \(MAX_X\)"):
        parse_json("[" + "1," * 4 + "1]", "it", 10, "MAX_X")
    with pytest.raises(ValueError, match="not readable JSON"):
        parse_json(b"\xff", "it")
