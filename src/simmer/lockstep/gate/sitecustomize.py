"""First on a lockstep program's ``PYTHONPATH``, before the shim: a Python the shim cannot
serve stops at once with one plain line, any other goes on to the shim's ``sitecustomize``.

The shim (``../shim/sitecustomize.py``) needs Python 3.8 or later (:data:`OLDEST_PYTHON`); an
older interpreter cannot even parse it, and Python only warns about a ``sitecustomize`` it
cannot import, then runs the program off the simulated clock. So this file is written in syntax that
every Python 2.7 and 3.x parses, and does nothing else: for a usable Python it leaves the path
and hands over to the next ``sitecustomize`` on it, the shim's.
"""

import os
import sys

OLDEST_PYTHON = (3, 8)
"""The oldest Python the shim serves (``simmer.lockstep.OLDEST_PYTHON``)."""


def _refuse():  # type: () -> None
    """Say in one line which Python this is and what to do, then end the program."""
    sys.stderr.write(
        "SimMeR: this program runs on Python %d.%d.%d (%s), and simmer run --program needs "
        "Python %d.%d or later (OLDEST_PYTHON) to put it on the simulated clock: put a newer "
        "python first on your PATH (activate its environment) or name it in --program, e.g. "
        '--program "python3.12 my_robot.py"\n'
        % (sys.version_info[:3] + (sys.executable or "python",) + OLDEST_PYTHON)
    )
    sys.stderr.flush()
    os._exit(2)


def _hand_over():  # type: () -> None
    """Import the shim's ``sitecustomize`` (the next on the path) in place of this one."""
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path[:] = [folder for folder in sys.path if os.path.abspath(folder or ".") != here]
    del sys.modules["sitecustomize"]
    import sitecustomize  # noqa: F401 (the shim's, once this folder is gone)


if __name__ == "sitecustomize":  # Python imports it at start-up; SimMeR reads OLDEST_PYTHON
    if os.environ.get("SIMMER_LOCKSTEP") and sys.version_info[:2] < OLDEST_PYTHON:
        _refuse()
    _hand_over()
