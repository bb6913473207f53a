"""One reader of a run folder's recordings (issue 29, item 4): ``events.jsonl`` and
``trace.csv`` are named, opened and parsed by ``simmer/record/reader.py`` alone; plots,
replays, their checks, sweeps and the command line read them through it, so its bounds
(docs/limits.md) and its one error hold for every reader. An AST scan of ``src/simmer``:
prose (a docstring, a help text, a message) may name the files, code may not.

Three rules, each of which the code before the reader broke (plots, the event log, the trace
check and the run folder each named or read the files themselves):

- a string that is one of the names as a path (``"trace.csv"``, ``"/events.jsonl"`` in an
  f-string) is in the reader only;
- a function that names the files (in its docstring, by such a string, or by a constant that
  holds one) opens or parses no file itself, unless it is the reader's or it writes;
- CSV is parsed only by the reader (and by ``sweep/results.py``, for a sweep's results.csv).
"""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

from helpers import REPO

SRC = REPO / "src" / "simmer"
READER = "record/reader.py"
NAMES = ("events.jsonl", "trace.csv", "scans.csv")
AS_PATH = re.compile(r"^\S*\b(events\.jsonl|trace\.csv|scans\.csv)$")
"""A string that is a recording's file name as a path (prose has spaces around it)."""
IN_PROSE = re.compile(r"events\.jsonl|trace\.csv|scans\.csv")
READING = {
    "read_text",
    "read_bytes",
    "readline",
    "readlines",
    "loads",
    "parse_json",
    "read_at_most",
    "reader",
    "DictReader",
    "loadtxt",
    "genfromtxt",
    "read_csv",
}
"""Calls that read or parse a file's contents, by the name called (``csv.reader``: ``reader``);
``open`` counts unless its mode writes."""
CSV_PARSERS = {"reader", "DictReader"}
OTHER_CSV = {"sweep/results.py"}
"""Modules that parse CSV of their own: a sweep's results.csv."""


@cache
def sources(root: Path) -> dict[str, str]:
    """The text of every module under ``root``, by its path relative to ``root``."""
    return {
        path.relative_to(root).as_posix(): path.read_text(encoding="utf-8")
        for path in sorted(root.rglob("*.py"))
    }


parsed = cache(ast.parse)


def modules(root: Path, *words: str) -> dict[str, ast.Module]:
    """The modules under ``root`` whose text holds one of ``words``, parsed: no other can
    match (parsing and walking every module took 2 CPU seconds)."""
    return {
        module: parsed(text)
        for module, text in sources(root).items()
        if any(word in text for word in words)
    }


def docstrings(tree: ast.Module) -> set[int]:
    """The ids of the string nodes that are docstrings (of the module, a class, a function)
    or a bare string under an assignment (an attribute's docstring)."""
    found = set()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if not isinstance(body, list):
            continue
        for statement in body:
            if isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant):
                found.add(id(statement.value))
    return found


def path_strings(tree: ast.Module) -> list[ast.Constant]:
    """The strings of ``tree`` that are a recording's file name as a path (not docstrings)."""
    prose = docstrings(tree)
    return [
        node
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and id(node) not in prose
        and AS_PATH.match(node.value.strip())
    ]


def name_constants(tree: ast.Module) -> set[str]:
    """Names assigned one of the file names (``TRACE = "trace.csv"``) in ``tree``."""
    found = set()
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant)):
            continue
        value = node.value.value
        if isinstance(value, str) and AS_PATH.match(value.strip()):
            found.update(t.id for t in node.targets if isinstance(t, ast.Name))
    return found


def called_name(call: ast.Call) -> str:
    function = call.func
    if isinstance(function, ast.Attribute):
        return function.attr
    return function.id if isinstance(function, ast.Name) else ""


def writes(call: ast.Call) -> bool:
    """Whether an ``open`` call's mode (its first two arguments or ``mode=``) writes."""
    modes = [*call.args[:2], *(k.value for k in call.keywords if k.arg == "mode")]
    return any(
        isinstance(m, ast.Constant) and isinstance(m.value, str) and set(m.value) & set("wax+")
        for m in modes
    )


def reads(function: ast.FunctionDef | ast.AsyncFunctionDef) -> list[str]:
    """The calls in ``function`` that read or parse a file, by line."""
    found = []
    for node in ast.walk(function):
        if isinstance(node, ast.Call):
            name = called_name(node)
            if name in READING or (name == "open" and not writes(node)):
                found.append(f"{node.lineno}: {name}()")
    return found


def names_the_files(
    function: ast.FunctionDef | ast.AsyncFunctionDef, constants: set[str], paths: set[int]
) -> bool:
    """Whether ``function`` names a recording's file: in its docstring, by a path string, or
    by a constant holding one."""
    if IN_PROSE.search(ast.get_docstring(function) or ""):
        return True
    for node in ast.walk(function):
        if id(node) in paths:
            return True
        if isinstance(node, ast.Name) and node.id in constants:
            return True
        if isinstance(node, ast.Attribute) and node.attr in constants:
            return True
    return False


def second_readers(trees: dict[str, ast.Module]) -> dict[str, list[str]]:
    """Functions outside the reader that name the files and read a file, with their reads."""
    constants = set().union(*(name_constants(tree) for tree in trees.values()))
    found = {}
    for module, tree in trees.items():
        if module == READER:
            continue
        paths = {id(node) for node in path_strings(tree)}
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                hits = reads(node) if names_the_files(node, constants, paths) else []
                if hits:
                    found[f"{module}:{node.name}"] = hits
    return found


def csv_parsers(trees: dict[str, ast.Module]) -> set[str]:
    """Modules that call ``csv.reader`` or ``csv.DictReader``."""
    return {
        module
        for module, tree in trees.items()
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and called_name(node) in CSV_PARSERS
    }


def test_the_scan_finds_a_second_reader() -> None:
    """Each rule catches code as it was before the reader (plots read the trace itself)."""
    tree = ast.parse(
        '"""Plots; reads ``trace.csv``."""\n'
        "import csv\n"
        'TRACE_FILE = "trace.csv"\n'
        "def read_run(folder):\n"
        "    return _rows(folder / TRACE_FILE)\n"
        "def _rows(path):\n"
        '    """The rows of a trace.csv."""\n'
        "    with path.open(newline='') as file:\n"
        "        return list(csv.reader(file))\n"
        "def write(path):\n"
        '    """Write events.jsonl."""\n'
        "    return open(path, 'wb')\n"
    )
    trees = {"record/plots.py": tree}
    assert [node.value for node in path_strings(tree)] == ["trace.csv"]
    assert name_constants(tree) == {"TRACE_FILE"}
    assert second_readers(trees) == {"record/plots.py:_rows": ["8: open()", "9: reader()"]}
    assert csv_parsers(trees) == {"record/plots.py"}


def test_only_the_reader_names_and_reads_the_recordings() -> None:
    named = modules(SRC, *NAMES)
    assert sorted(node.value for node in path_strings(named[READER])) == sorted(NAMES)
    naming = {module for module, tree in named.items() if path_strings(tree)}
    assert naming == {READER}, "name events.jsonl and trace.csv by simmer.record.reader's constants"
    constants = set().union(*(name_constants(tree) for tree in named.values()))
    assert constants == {"EVENTS", "TRACE", "SCANS"}
    found = second_readers(modules(SRC, *NAMES, *constants))
    assert found == {}, "read events.jsonl and trace.csv with simmer.record.reader"
    assert csv_parsers(modules(SRC, *CSV_PARSERS)) == {READER, *OTHER_CSV}


def test_plots_replays_and_the_run_folder_read_through_the_reader() -> None:
    """The reader's users import it (so the scan above is not empty because they moved)."""
    users = {
        module
        for module, tree in modules(SRC, "simmer.record.reader").items()
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom) and node.module == "simmer.record.reader"
    }
    assert {"record/plots.py", "record/runfolder.py", "view/replay_model.py"} <= users
