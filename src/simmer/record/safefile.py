"""Writing a file into a folder someone else made (a run folder), so that whatever is already
at its name cannot send the bytes elsewhere.

A run folder is data: one handed to a TA may hold ``report.md`` as a symbolic link to
``~/.bashrc``. Every file SimMeR writes into a run folder (``report.md``, ``report.json``, the
plots, a rendered clip) and every video goes through :class:`SafeFile`:

- a run folder must be a folder, not a symbolic link to one (a path the user typed for a video
  of their own, ``-o`` or ``--video``, is theirs, links and all);
- the name must be free or hold a regular file: a symbolic link, a folder, a pipe or a device
  there is refused (:class:`~simmer.errors.UnsafeOutput`, one line) and left as it is;
- the bytes go into a new file beside it, created under a random name with ``O_EXCL`` (so
  nothing the folder holds is opened), which :func:`os.replace` then puts at the name.

Why a new file and a rename, rather than opening the name with ``O_NOFOLLOW``: the rename
replaces the name itself and never follows what is there, so even a link put in its place
after the check is replaced, not written through, and a hard link to a file elsewhere (a
regular file, which ``O_NOFOLLOW`` would open and overwrite) loses the name while the file
elsewhere keeps its bytes; it works on Windows, which has no
``O_NOFOLLOW``; a reader never sees half a file, and a plot stopped midway leaves the old one
whole; and matplotlib's ``savefig`` and PyAV write the new file by its path like any other.
"""

from __future__ import annotations

import os
import secrets
import stat
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

from simmer.errors import UnsafeOutput

NEW_FILE_FLAGS = (
    os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
)
"""How the new file is created: only if nothing is at its name, never through a link."""


def _what(mode: int) -> str:
    """What a non-regular file is, in words."""
    if stat.S_ISLNK(mode):
        return "a symbolic link"
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a pipe"
    return "not a regular file (a device or a socket)"


def check_folder(folder: Path, *, missing_ok: bool = False) -> None:
    """Raise :class:`UnsafeOutput` unless ``folder`` is a real folder, not a link to one
    (or, with ``missing_ok``, is not there yet)."""
    try:
        mode = os.lstat(folder).st_mode
    except FileNotFoundError:
        if missing_ok:
            return
        raise UnsafeOutput(f"cannot write into {folder}: there is no such folder") from None
    except OSError as exc:
        raise UnsafeOutput(f"cannot write into {folder}: {exc.strerror or exc}") from None
    if not stat.S_ISDIR(mode):
        raise UnsafeOutput(
            f"{folder} is {_what(mode)}, not a folder of SimMeR's files: SimMeR writes only "
            "into a real folder; give the folder's own path"
        )


def check_target(path: Path, *, run_folder: bool = True) -> None:
    """Raise :class:`UnsafeOutput` unless ``path`` may be written: its folder a real folder
    (not a link, when it is a run folder) and its name free or a regular file."""
    if run_folder:
        check_folder(path.parent)
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as exc:
        raise UnsafeOutput(f"cannot write {path}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(mode):
        raise UnsafeOutput(
            f"{path} is {_what(mode)}: SimMeR writes only a regular file there, not through "
            "it; move it away (or delete it) and try again"
        )


class SafeFile:
    """A file about to be written at ``path`` (:func:`check_target` first): write
    :attr:`temp`, then :meth:`commit` puts it at ``path`` (or :meth:`discard` drops it).
    ``run_folder``: ``path`` is in a folder someone else may have made, which must not be a
    link."""

    def __init__(self, path: str | Path, *, run_folder: bool = True) -> None:
        self.path = Path(path)
        check_target(self.path, run_folder=run_folder)
        name = f".{self.path.name[:64]}.{secrets.token_hex(6)}{self.path.suffix[:16]}"
        self.temp = self.path.with_name(name)
        """The new file (its suffix the target's: writers choose the format by it)."""
        os.close(os.open(self.temp, NEW_FILE_FLAGS, 0o666))

    def commit(self) -> None:
        """Put the written file at the name (whatever is there now is replaced, not followed)."""
        try:
            os.replace(self.temp, self.path)
        except OSError:
            self.discard()
            raise

    def discard(self) -> None:
        """Drop the written file; the name keeps what it held."""
        with suppress(OSError):
            os.unlink(self.temp)


@contextmanager
def replacing(path: str | Path, *, run_folder: bool = True) -> Iterator[Path]:
    """``with replacing(path) as temp:`` write ``temp``; at the end it is put at ``path``
    (dropped if the block raised). :class:`UnsafeOutput` before anything is written if ``path``
    may not be (:func:`check_target`)."""
    file = SafeFile(path, run_folder=run_folder)
    try:
        yield file.temp
    except BaseException:
        file.discard()
        raise
    file.commit()


def write_bytes(path: str | Path, data: bytes, *, run_folder: bool = True) -> None:
    """Write ``data`` at ``path``, safely (:func:`replacing`)."""
    with replacing(path, run_folder=run_folder) as temp:
        temp.write_bytes(data)


def write_text(path: str | Path, text: str, *, run_folder: bool = True) -> None:
    """Write ``text`` (UTF-8) at ``path``, safely (:func:`replacing`)."""
    write_bytes(path, text.encode("utf-8"), run_folder=run_folder)
