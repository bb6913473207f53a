"""A box for a program SimMeR does not trust (a team's, in ``simmer grade``): its own copy of
its folder, limits on what it may use, and (Linux) no reach beyond its box.

:class:`BoxLimits` says the limits; :func:`make_box` copies a team's folder into a scratch
folder of the run's (links copied as links, never followed: a link to another team's folder
is not read with the grader's rights); :func:`boxed_command` puts the launcher
(:mod:`simmer.lockstep.boxlaunch`) before the program's command line, which sets the box up
in the program's own process and then becomes the program. What is enforced where:

- **Linux**: CPU seconds (``RLIMIT_CPU``: SIGXCPU, then SIGKILL), address space
  (``RLIMIT_AS``: MemoryError), file size (``RLIMIT_FSIZE``: "File too large"), processes
  (``RLIMIT_NPROC``: fork fails; as root each box runs as a user id of its own, so the count
  is the box's; as another user it is that user's processes, plus the limit), open files
  (``RLIMIT_NOFILE``); Landlock (kernel 5.13+): reading only the system's, Python's and
  SimMeR's files and writing only in its box, so another team's folder is refused; (6.7+)
  TCP connections to this run's ports only, and no listening; (6.12+) no signals to
  processes outside the box; a network namespace of its own (user namespaces, or root),
  holding only the simulator's ports (:mod:`simmer.lockstep.netns`): no other port of this
  machine, no other machine, no UDP.
- **macOS**: the resource limits, except the address space (macOS does not enforce it) and
  with processes counted per user; no file or network confinement.
- **Windows**: only the copy of the folder and the run's time limits.
"""

from __future__ import annotations

import json
import os
import shutil
import site
import sys
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from simmer.lockstep.netns import Network

LAUNCHER = Path(__file__).resolve().parent / "boxlaunch.py"
"""The file run before a boxed program (standard library only)."""
BOX_UID_BASE = 200_000
"""As root, a box runs as user ``BOX_UID_BASE + (worker's pid mod 100,000)``: an id no
account has, of its own for each worker, so its process limit counts only its processes."""
MAX_BOX_BYTES = 100 * 1024 * 1024
"""Bytes of a team's folder copied into its box for each run (a program and a few data
files are some kilobytes; a folder with videos or a virtual environment in it is refused)."""
MAX_BOX_FILES = 5_000
"""Files and folders in a team's folder copied into its box for each run."""
SYSTEM_READ = ("/usr", "/lib", "/lib64", "/lib32", "/bin", "/sbin", "/etc", "/opt", "/proc", "/sys")
"""What a boxed program may read besides Python's installations, SimMeR and its box."""
DEVICES = ("/dev/null", "/dev/zero", "/dev/urandom", "/dev/random", "/dev/tty", "/dev/pts")
"""Devices a boxed program may read and write."""


@dataclass(frozen=True)
class BoxLimits:
    """What a boxed program may use (None: no limit of that kind). ``landlock``: confine its
    files, ports and signals where the kernel can (Linux). ``network``: a network of its own
    holding only the simulator's ports, where the machine can make one
    (:mod:`simmer.lockstep.netns`)."""

    cpu_seconds: float | None = 60.0
    memory_mb: int | None = 1024
    file_mb: int | None = 16
    processes: int | None = 32
    open_files: int | None = 256
    landlock: bool = True
    network: bool = True


@dataclass(frozen=True)
class Box:
    """One run's box: its limits, the copy of the team's folder the program works in and
    its temporary folder (both from :func:`make_box`)."""

    limits: BoxLimits
    work: Path
    tmp: Path
    network: Network | None = None
    """The run's network namespace (None: the machine's network)."""


def check_folder(folder: Path) -> None:
    """Raise ValueError (naming the limit) if ``folder`` is too big to copy for each run."""
    count = size = 0
    for root, dirs, files in os.walk(folder):
        for name in files:
            path = Path(root, name)
            if not path.is_symlink():
                size += path.stat().st_size
        count += len(dirs) + len(files)
        if count > MAX_BOX_FILES or size > MAX_BOX_BYTES:
            raise ValueError(
                f"{folder} holds more than {MAX_BOX_FILES:,} files (MAX_BOX_FILES) or "
                f"{MAX_BOX_BYTES // 2**20} MB (MAX_BOX_BYTES), copied for every run: leave "
                "only the program and its data in it (no videos, no virtual environment)"
            )


def make_box(folder: Path, scratch: Path) -> tuple[Path, Path]:
    """Copy ``folder`` into ``scratch``/box (links as links) and make ``scratch``/tmp; the two
    folders. ``scratch`` is opened to other users for passing through only (a box may run as
    a user of its own)."""
    work, tmp = scratch / "box", scratch / "tmp"
    shutil.copytree(folder, work, symlinks=True)
    tmp.mkdir()
    scratch.chmod(0o711)
    return work, tmp


def read_roots(program: str) -> list[str]:
    """Folders a boxed program may read: the system's, this Python's installation and
    packages, SimMeR's own (the shim), and the installation of the program's interpreter."""
    import simmer

    roots = [*SYSTEM_READ, sys.prefix, sys.base_prefix, sys.exec_prefix]
    roots += [*site.getsitepackages(), str(Path(simmer.__file__).resolve().parent.parent)]
    interpreter = Path(program).resolve()
    roots.append(str(interpreter.parent.parent))  # .../bin/python -> ...
    return sorted({os.path.realpath(root) for root in roots})


def boxed_command(args: list[str], box: Box, ports: list[int]) -> list[str]:
    """The command line that starts ``args`` in ``box`` (``args[0]`` a full path), allowed
    to connect to ``ports`` only."""
    settings = asdict(box.limits)
    settings.update(
        folder=str(box.work),
        tmp=str(box.tmp),
        read=read_roots(args[0]),
        write=[str(box.work), str(box.tmp)],
        devices=list(DEVICES),
        ports=sorted(ports),
        report=str(box.tmp / "box.json"),
    )
    if os.name == "posix" and os.getuid() == 0:
        settings["uid"] = BOX_UID_BASE + os.getpid() % 100_000
    if box.network is not None:  # inherited by the launcher, which joins them
        settings["namespaces"] = dict(zip(box.network.kinds, box.network.namespaces, strict=True))
    return [sys.executable, "-I", str(LAUNCHER), json.dumps(settings), "--", *args]


def box_environment(env: Mapping[str, str], box: Box) -> dict[str, str]:
    """The program's environment in its box: its home and temporary folder are the box's."""
    boxed = dict(env)
    boxed["HOME"] = str(box.work)
    for name in ("TMPDIR", "TEMP", "TMP"):
        boxed[name] = str(box.tmp)
    return boxed
