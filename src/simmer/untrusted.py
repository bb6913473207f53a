"""Text and JSON that SimMeR did not write itself, made safe to draw and to parse.

A control program chooses what it sends (a belief's labels, a command, its name) and a run
folder holds whatever its owner put there, so both are data to be checked, never trusted:

- :func:`drawable` is the one sanitiser every string passes before it reaches a font (the
  window's, the off-screen renderer's and matplotlib's): a NUL made pygame raise, a lone
  surrogate could not be encoded, a bidirectional or zero-width character alone drew "Text
  has zero width" and ended the run, and a ``$`` pair in matplotlib parsed as mathematics.
- :func:`parse_json` is the one JSON reader for such text: Python's :mod:`json` recurses once
  per level, so ``[`` x 3,000 raised RecursionError (a traceback where a plain line belongs);
  the depth is counted first, without recursion, and the size is bounded before parsing.

This module imports nothing of SimMeR's, so every layer may use it (docs/architecture.md).
"""

from __future__ import annotations

import json
import re
import unicodedata
from collections.abc import Callable
from pathlib import Path
from typing import Any

MAX_DRAWN_CHARS = 200
"""Characters of one drawn string; the rest is cut and ``...`` ends it. The widest place
text is drawn (a window 1,600 pixels wide, 18-pixel letters) shows fewer than 200."""
REPLACEMENT = "?"
"""What a character that cannot be drawn becomes. Not U+FFFD: pygame's default font has no
glyph for it."""
CUT = "..."
"""Ends a string cut to :data:`MAX_DRAWN_CHARS`."""

_NOT_DRAWN = frozenset({"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"})
"""Unicode categories never drawn: control and format characters (NUL, ESC, every
bidirectional control U+202A-U+202E and U+2066-U+2069, the zero-width characters U+200B-U+200F
and the BOM U+FEFF), surrogates, private-use and unassigned code points, line and paragraph
separators."""

MAX_JSON_DEPTH = 32
"""Arrays and objects nested in one JSON text. SimMeR's own nest at most 6 (a manifest's
configuration); Python's json module recurses once a level and fails near 1,000."""
MAX_JSON_CHARS = 16 * 1024 * 1024
"""Characters of one JSON text, unless the reader asks for fewer: a run folder's manifest and
the maze's document frame are bounded by 16 MB too."""

_STRING = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)
"""A JSON string, escapes included (brackets in it are text, not nesting)."""
_PARENTHESES = bytes.maketrans(b"[]{}", b"()()")
_NOT_BRACKETS = bytes(c for c in range(256) if c not in b"[]{}")
"""Every byte but the brackets: no byte of a UTF-8 character beyond ASCII is one."""


def drawable(text: str, known: Callable[[str], bool] | None = None) -> str:
    """``text`` as it may be drawn: each character of a category in :data:`_NOT_DRAWN` (or
    that ``known``, the font's own test, says it has no glyph for) replaced by
    :data:`REPLACEMENT`, and at most :data:`MAX_DRAWN_CHARS` characters (a longer text is cut
    and ends in :data:`CUT`). Printable ASCII comes back unchanged."""
    if len(text) > MAX_DRAWN_CHARS:
        text = text[: MAX_DRAWN_CHARS - len(CUT)] + CUT
    if text.isascii() and text.isprintable():
        return text
    return "".join(
        REPLACEMENT
        if unicodedata.category(c) in _NOT_DRAWN or (known is not None and not known(c))
        else c
        for c in text
    )


def nests_deeper(text: str | bytes, limit: int = MAX_JSON_DEPTH) -> bool:
    """Whether the arrays and objects of JSON ``text`` nest more than ``limit`` deep, counted
    without recursion: brackets inside strings are text, and the deepest point of the running
    count of brackets opened less those closed is the depth (a bracket never closed counts,
    since the parser recurses into it before it finds the end). About 70 us for a 50 KB show
    message of 2,000 particles, where :func:`json.loads` takes 2 ms."""
    import numpy as np  # here: importing simmer.client loads no numpy (tests/test_client.py)

    data = text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text
    if b'"' in data:
        data = _STRING.sub(b"", data)
    nesting = data.translate(_PARENTHESES, _NOT_BRACKETS)
    steps = 81 - 2 * np.frombuffer(nesting, dtype=np.int8)  # "(" is 40, ")" 41
    return bool(np.cumsum(steps, dtype=np.int32).max(initial=0) > limit)


def parse_json(
    text: str | bytes, what: str, max_chars: int = MAX_JSON_CHARS, limit: str = "MAX_JSON_CHARS"
) -> Any:
    """The value of JSON ``text``; ValueError, one line saying ``what`` it is and naming the
    limit, if it is longer than ``max_chars`` characters (or bytes; the constant named
    ``limit``), nests deeper than :data:`MAX_JSON_DEPTH`, or is not JSON."""
    if len(text) > max_chars:
        raise ValueError(
            f"{what} is {len(text):,} characters, over the limit of {max_chars:,} ({limit})"
        )
    if nests_deeper(text):
        raise ValueError(
            f"{what} is not readable JSON: it nests lists or objects more than "
            f"{MAX_JSON_DEPTH} deep (MAX_JSON_DEPTH)"
        )
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ValueError(f"{what} is not readable JSON: {exc}") from None
    try:
        return json.loads(text)
    except ValueError as exc:  # json.JSONDecodeError is a ValueError
        raise ValueError(f"{what} is not readable JSON: {exc}") from None


def read_at_most(path: Path, limit: int, limit_name: str, then: str) -> bytes:
    """The bytes of ``path``, read to at most ``limit`` (a file in a folder someone gave us
    may be any size); past it a ValueError naming the file and the limit, ending in ``then``."""
    with path.open("rb") as file:
        data = file.read(limit + 1)
    if len(data) > limit:
        raise ValueError(f"{path} is larger than {limit:,} bytes ({limit_name}), {then}")
    return data
