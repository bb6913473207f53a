"""``simmer new DIR``: a folder of the student's own for Lab 1, and for the project and
localization pages too (``--project``, ``--localization``).

It holds the lab's rover (``my_rover.toml``), the example programs, sweep files whose results
land in the folder ``simmer sweep`` runs from, and a short README pointing at the lab page, so
that every command of ``docs/lab1.md`` runs from it; with :data:`PARTS` chosen, the files the
project's and localization's pages use too, so that every command of those pages runs from it
as written. The files are package data (``simmer/data/new``), so this works from an installed
package as from a clone.
"""

from __future__ import annotations

from collections.abc import Iterable
from importlib.resources import files
from pathlib import Path

import simmer
from simmer.errors import FolderExists

TEMPLATE = "data/new"
LAB_PAGE = "docs/lab1.md"
PARTS: dict[str, tuple[str, ...]] = {
    "project": ("project.toml", "project_delivery.py", "sweep_project.toml",
                "sweep_project_starts.toml"),
    "localization": ("histogram_localization.py", "particle_filter.py",
                     "sweep_localization.toml", "project.toml"),
}  # fmt: skip
"""The template's files each page beyond Lab 1 adds (``simmer new --project``,
``--localization``); every other file of the template is Lab 1's, always written."""


def lab_page() -> str:
    """Where the lab page is: its full path in a clone of SimMeR, else its place in the
    repository."""
    page = Path(simmer.__file__).resolve().parents[2] / LAB_PAGE
    return str(page) if page.is_file() else f"{LAB_PAGE} in SimMeR's repository"


def new_folder(destination: Path, parts: Iterable[str] = ()) -> list[Path]:
    """Write the Lab 1 folder at ``destination`` (made if missing), with the files of the
    ``parts`` named (keys of :data:`PARTS`); the files written.

    Raises :class:`FolderExists` if ``destination`` is not an empty folder, and ``OSError``
    if it cannot be written.
    """
    if destination.exists() and (not destination.is_dir() or any(destination.iterdir())):
        what = "a folder with files in it" if destination.is_dir() else "a file"
        raise FolderExists(
            f"{destination} is {what} already; give a new folder's name (nothing was changed)"
        )
    chosen = set(parts)
    unknown = chosen - PARTS.keys()
    if unknown:
        raise ValueError(f"no part {sorted(unknown)[0]!r}; the parts are: {', '.join(PARTS)}")
    extra = {name for files_ in PARTS.values() for name in files_}
    wanted = {name for part in chosen for name in PARTS[part]}
    destination.mkdir(parents=True, exist_ok=True)
    written = []
    template = files("simmer").joinpath(TEMPLATE)
    for source in sorted(template.iterdir(), key=lambda f: f.name):
        if not source.is_file():
            continue  # __pycache__, made when an install compiles the example programs
        if source.name in extra and source.name not in wanted:
            continue
        text = source.read_text(encoding="utf-8")
        if source.name == "README.md":
            text = text.replace("{lab_page}", lab_page())
        target = destination / source.name
        target.write_text(text, encoding="utf-8", newline="\n")
        written.append(target)
    return written
