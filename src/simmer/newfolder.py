"""``simmer new DIR``: a folder of the student's own for Lab 1.

It holds the lab's rover (``my_rover.toml``), the example programs, sweep files whose results
land in the folder ``simmer sweep`` runs from, and a short README pointing at the lab page, so
that every command of ``docs/lab1.md`` runs from it. The files are package data
(``simmer/data/new``), so this works from an installed package as from a clone.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

import simmer
from simmer.errors import FolderExists

TEMPLATE = "data/new"
LAB_PAGE = "docs/lab1.md"


def lab_page() -> str:
    """Where the lab page is: its full path in a clone of SimMeR, else its place in the
    repository."""
    page = Path(simmer.__file__).resolve().parents[2] / LAB_PAGE
    return str(page) if page.is_file() else f"{LAB_PAGE} in SimMeR's repository"


def new_folder(destination: Path) -> list[Path]:
    """Write the Lab 1 folder at ``destination`` (made if missing); the files written.

    Raises :class:`FolderExists` if ``destination`` is not an empty folder, and ``OSError``
    if it cannot be written.
    """
    if destination.exists() and (not destination.is_dir() or any(destination.iterdir())):
        what = "a folder with files in it" if destination.is_dir() else "a file"
        raise FolderExists(
            f"{destination} is {what} already; give a new folder's name (nothing was changed)"
        )
    destination.mkdir(parents=True, exist_ok=True)
    written = []
    template = files("simmer").joinpath(TEMPLATE)
    for source in sorted(template.iterdir(), key=lambda f: f.name):
        if not source.is_file():
            continue  # __pycache__, made when an install compiles the example programs
        text = source.read_text(encoding="utf-8")
        if source.name == "README.md":
            text = text.replace("{lab_page}", lab_page())
        target = destination / source.name
        target.write_text(text, encoding="utf-8", newline="\n")
        written.append(target)
    return written
