"""TOML that does not parse, told in plain words with its line (``simmer check``).

tomllib says ``Cannot overwrite a value (at line 42, column 13)``: true, but it does not say
that the key was already set on line 41, which is what a student sees after uncommenting a
line beside the one it was meant to replace. So a key or table written twice is found again
here, by a small scan of the file's statements, and both lines are named. Every other
tomllib message is reworded, and its line always goes into :attr:`ConfigIssue.line`.

The same scan gives the problems validation finds in a file that parses their lines
(:func:`with_lines`): ``drives.w0.motors[1]: no motor 'm2'`` points at the ``motors`` line.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass, replace
from typing import Literal

from simmer.errors import ConfigIssue

_WHERE = re.compile(
    r"(?P<what>.*?) \(at (?:line (?P<line>\d+), column (?P<column>\d+)|end of document)\)", re.S
)
_TWICE = ("Cannot overwrite", "Cannot declare", "Cannot redefine", "Cannot mutate")
"""tomllib's messages for a key or table written twice (or as both a value and a table)."""
_PLAIN = {
    "Invalid value": 'this value cannot be read: text needs quotes ("ultrasonic"), true and '
    "false are lower case, and a list is written [1, 2]",
    "Unterminated string": "a quoted text is not closed: add the closing quote",
    "Illegal character '\\n'": "a quoted text is not closed on its line: add the closing quote",
    "Expected newline or end of document after a statement": "there is more after a complete "
    "setting on this line: one setting per line (check quotes, commas and brackets)",
    "Invalid statement": "this line is neither a setting (key = value) nor a table header "
    "such as [sensors.u0]",
    "Expected '=' after a key in a key/value pair": "a key must be followed by = and a value",
    "Invalid initial character for a key part": "a key is missing or starts with a character "
    "a key cannot have (letters, digits, _ and - only, or put it in quotes)",
    "Unclosed array": "a list opened with [ is not closed with ] (or a comma is missing)",
    "Unclosed inline table": "a { ... } is not closed with } on the same line",
    "Expected ']' at the end of a table declaration": "a table header must end with ], "
    "e.g. [sensors.u0]",
    "Expected ']]' at the end of an array declaration": "an array of tables header must end "
    "with ]]",
}
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def toml_issue(exc: tomllib.TOMLDecodeError, text: str) -> ConfigIssue:
    """The problem tomllib found in ``text``, in plain words, with its line."""
    found = _WHERE.fullmatch(str(exc))
    what = found["what"] if found else str(exc)
    said_line = found["line"] if found else None
    column = found["column"] if found else None
    at_end = said_line is None  # "at end of document": the last line
    line = max(1, len(text.splitlines())) if said_line is None else int(said_line)
    if what.startswith(_TWICE):
        twice = _written_twice(text, line, at_end=at_end)
        if twice is not None:
            return twice
        plain = "a key or a table is written twice: keep one of them"
    elif what.startswith("Duplicate inline table key"):
        plain = f"d{what[1:]} inside {{ ... }}: keep one"
    else:
        plain = _PLAIN.get(what, what[:1].lower() + what[1:])
    where = f"line {line}, column {column}" if column else f"line {line}"
    return ConfigIssue("", f"not valid TOML at {where}: {plain}", line)


def with_lines(issues: list[ConfigIssue], text: str) -> list[ConfigIssue]:
    """``issues`` with the line of each key found in ``text`` (the key's own line; for a key
    not written there, its table's header), in the order of the file."""
    lines = key_lines(text)
    placed = [
        issue if issue.line is not None else replace(issue, line=_line_of(lines, issue.key))
        for issue in issues
    ]
    return sorted(placed, key=lambda issue: issue.line if issue.line is not None else 1 << 62)


def key_lines(text: str) -> dict[tuple[str, ...], int]:
    """The first line of every key and table header written in ``text`` (what the scan
    follows; nothing for a file it cannot)."""
    lines: dict[tuple[str, ...], int] = {}
    try:
        for statement in _statements(text):
            for end in range(1, len(statement.path) + 1):  # a dotted key's tables too
                lines.setdefault(statement.path[:end], statement.first)
    except ValueError:
        return {}
    return lines


def _line_of(lines: dict[tuple[str, ...], int], key: str) -> int | None:
    """The line of ``key`` (``drives.w0.motors[1]``), or of the nearest table holding it."""
    path = tuple(re.sub(r"\[\d+\]", "", key).split("."))
    for end in range(len(path), 0, -1):
        if path[:end] in lines:
            return lines[path[:end]]
    return None


# ----------------------------------------------------------------------------- the scan


@dataclass(frozen=True)
class _Statement:
    """One top-level statement: a key set (``key``) or a table header (``table``, ``array``
    for ``[[...]]``), with its full key path and its first and last lines."""

    kind: Literal["key", "table", "array"]
    path: tuple[str, ...]
    first: int
    last: int
    written: int = 1
    """How many parts of ``path`` the statement writes (``a.b = 1`` in ``[t]``: 2)."""


def _written_twice(text: str, line: int, *, at_end: bool) -> ConfigIssue | None:
    """The key or table that tomllib refused on ``line`` and the line that set it first."""
    values: dict[tuple[str, ...], _Statement] = {}  # keys set to a value
    tables: dict[tuple[str, ...], _Statement] = {}  # [table] headers and dotted-key tables
    try:
        for statement in _statements(text):
            earlier = _clash(statement, values, tables)
            if earlier is not None:
                if at_end or statement.first <= line <= statement.last:
                    return _twice_issue(earlier, statement)
                return None
            path = statement.path
            if statement.kind == "key":
                values[path] = statement
                for end in range(len(path) - statement.written + 1, len(path)):
                    tables.setdefault(path[:end], statement)  # the tables a dotted key makes
            elif statement.kind == "table":
                tables[path] = statement
    except ValueError:  # the scan could not follow the file: tomllib's words will do
        return None
    return None


def _clash(
    statement: _Statement,
    values: dict[tuple[str, ...], _Statement],
    tables: dict[tuple[str, ...], _Statement],
) -> _Statement | None:
    """The earlier statement that ``statement`` writes over, if any."""
    path = statement.path
    for end in range(1, len(path) + 1):  # the key, or a part of its path, holds a value
        if path[:end] in values:
            return values[path[:end]]
    return tables.get(path)


def _twice_issue(earlier: _Statement, later: _Statement) -> ConfigIssue:
    lines = f"on lines {earlier.first} and {later.first}"
    if earlier.path == later.path and earlier.kind == later.kind == "key":
        message = f"is set twice, {lines}: keep one, and delete the other or comment it out with #"
    elif earlier.path == later.path and earlier.kind == later.kind:
        header = _dotted(later.path)
        message = (
            f"the table [{header}] is written twice, {lines}: keep one [{header}] line and put "
            "all its settings under it"
        )
    else:
        message = (
            f"{_shown(later)} on line {later.first} clashes with {_shown(earlier)} on line "
            f"{earlier.first}: a key that holds a value cannot also be a table, or be set "
            "again; keep one of them"
        )
    return ConfigIssue(_dotted(later.path), message, later.first)


def _shown(statement: _Statement) -> str:
    """A statement as written, in short: ``[a.b]`` or ``a.b = ...``."""
    path = _dotted(statement.path)
    return f"`{path} = ...`" if statement.kind == "key" else f"[{path}]"


def _dotted(path: tuple[str, ...]) -> str:
    return ".".join(p if _BARE_KEY.fullmatch(p) else f'"{p}"' for p in path)


def _statements(text: str) -> Iterator[_Statement]:
    """The top-level statements of ``text``; ValueError where the scan cannot follow it."""
    scan = _Scanner(text)
    table: tuple[str, ...] = ()
    arrays: dict[tuple[str, ...], int] = {}
    while (start := scan.next_statement()) is not None:
        first = scan.line
        if scan.text.startswith("[[", start):
            path = _key_path(scan.until("]]", start + 2))
            arrays[path] = arrays.get(path, 0) + 1
            table = (*path, f"[{arrays[path]}]")  # each element has keys of its own
            yield _Statement("array", path, first, first)
        elif scan.text[start] == "[":
            table = _key_path(scan.until("]", start + 1))
            yield _Statement("table", table, first, first)
        else:
            key = _key_path(scan.until("=", start))
            scan.skip_value()
            yield _Statement("key", table + key, first, scan.line, len(key))


def _key_path(written: str) -> tuple[str, ...]:
    """``a."b.c" . d`` -> ``("a", "b.c", "d")``, read by tomllib itself."""
    try:
        data = tomllib.loads(f"{written.strip()} = 0")
    except tomllib.TOMLDecodeError:
        raise ValueError(written) from None
    path: list[str] = []
    node: object = data
    while isinstance(node, dict):
        (key, node), *_ = node.items()
        path.append(key)
    return tuple(path)


class _Scanner:
    """Walks TOML text statement by statement, counting lines, skipping strings and comments."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.pos = 0
        self.line = 1

    def next_statement(self) -> int | None:
        """Move to the next statement's first character; None at the end."""
        text = self.text
        while self.pos < len(text):
            char = text[self.pos]
            if char == "#":
                self._to_line_end()
            elif char in " \t\r\n":
                self._advance(1)
            else:
                return self.pos
        return None

    def until(self, end: str, start: int) -> str:
        """The text from ``start`` to ``end`` (outside quotes), moving past ``end``."""
        self.pos = start
        while self.pos < len(self.text):
            if self.text.startswith(end, self.pos):
                found = self.text[start : self.pos]
                self._advance(len(end))
                return found
            char = self.text[self.pos]
            if char == "\n":
                break
            if char in "\"'":
                self._skip_string()
            else:
                self._advance(1)
        raise ValueError(f"no {end!r} on line {self.line}")

    def skip_value(self) -> None:
        """Move past a value: nested brackets, strings and comments, to the end of its line."""
        depth = 0
        text = self.text
        while self.pos < len(text):
            char = text[self.pos]
            if char in "\"'":
                self._skip_string()
            elif char == "#":
                self._to_line_end()
            elif char == "\n" and depth == 0:
                return
            else:
                depth += (char in "[{") - (char in "]}")
                self._advance(1)

    def _skip_string(self) -> None:
        text = self.text
        quote = text[self.pos]
        triple = text.startswith(quote * 3, self.pos)
        end = quote * 3 if triple else quote
        self._advance(len(end))
        while self.pos < len(text):
            if quote == '"' and text[self.pos] == "\\":
                self._advance(2)
            elif text.startswith(end, self.pos):
                while triple and text.startswith(quote, self.pos + 3):  # """a"""" ends later
                    self._advance(1)
                self._advance(len(end))
                return
            elif text[self.pos] == "\n" and not triple:
                raise ValueError(f"unterminated string on line {self.line}")
            else:
                self._advance(1)
        raise ValueError("unterminated string")

    def _to_line_end(self) -> None:
        end = self.text.find("\n", self.pos)
        self.pos = len(self.text) if end < 0 else end

    def _advance(self, count: int) -> None:
        self.line += self.text.count("\n", self.pos, self.pos + count)
        self.pos += count
