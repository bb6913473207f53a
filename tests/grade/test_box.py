"""The box, tested for what it really enforces here (Linux): a fork bomb, a memory hog, a disk
filler, an infinite loop, a program reading another team's folder and three that flood the
link (commands without reading, a line without end, connections without end) are each
stopped or refused and reported; the good team's results are the same as graded alone; no process of
theirs is left behind."""

from __future__ import annotations

import csv
import os
import shutil
import sys
import tempfile
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import pytest

from grade_support import GOOD, grading_folder
from simmer.grade import load_grading, run_grading
from simmer.lockstep.box import BOX_UID_BASE
from simmer.lockstep.netns import unavailable
from simmer.proctree import descendants
from simmer.sweep import local_pool
from simmer.sweep.engine import Engine

FORK_BOMB = """import os, signal, sys
first = os.getpid()
while True:
    try:
        os.fork()  # parent and children alike go on forking
    except OSError as exc:
        if os.getpid() != first:
            signal.pause()  # a child: waits to be stopped with the run
        print("fork refused:", exc, flush=True)
        sys.exit(3)
"""
MEMORY_HOG = """hog = []
while True:
    hog.append(bytearray(50 * 1024 * 1024))
"""
DISK_FILLER = """block = b"x" * (1 << 20)
with open("fill.bin", "wb") as file:
    while True:
        file.write(block)
        file.flush()
"""
LOOP = """while True:
    pass
"""
SPY = """from pathlib import Path
secret = Path(TARGET)
print("trying", secret.name, flush=True)
print(secret.read_text()[:100])
"""
FLOOD = """import os, socket
link = socket.create_connection(("127.0.0.1", int(os.environ["SIMMER_PORT"])))
while True:
    link.sendall(b"u0\\n" * 1000)  # as fast as it can, never reading a reply
"""
ENDLESS_LINE = """import os, socket
link = socket.create_connection(("127.0.0.1", int(os.environ["SIMMER_PORT"])))
while True:
    link.sendall(b"w" * 65536)  # one line that never ends
"""
OPENER = """import os, socket
held = []
while True:  # connections without end, none closed
    held.append(socket.create_connection(("127.0.0.1", int(os.environ["SIMMER_PORT_RX"]))))
"""
LIMITS = """[limits]
cpu_seconds = 3
memory_mb = 400
file_mb = 8
processes = 16
open_files = 64
"""


def _command(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace")
    except OSError:
        return ""


def _state(pid: int) -> str:
    """A process's state, parent and user (what a failure shows of one left behind)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return "gone"
    return " ".join(
        line for line in status.splitlines() if line.startswith(("State", "PPid", "Uid"))
    )


def _box_users(pools: list[Any]) -> list[int]:
    """Processes running as the box users of these pools' workers (as root each worker's boxes
    run as ``BOX_UID_BASE`` + its pid): a test's own, not another worker's grading."""
    users = {BOX_UID_BASE + pid % 100_000 for pool in pools for pid in pool.worker_pids()}
    assert users, "the pools' workers said their pids"
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if entry.stat().st_uid in users:
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


def _tracked_pool(workers: int, pools: list[Any]) -> Engine:
    """:func:`local_pool`, each pool it makes kept in ``pools`` (whose box users to look for)."""
    make = local_pool(workers)

    def tracked() -> Executor:
        pool = make()
        pools.append(pool)
        return pool

    return tracked


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as file:
        return list(csv.DictReader(file))


@pytest.mark.slow
@pytest.mark.timeout(900)  # 10 program runs up to their limits (30 wall s): room on busy cores
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the box's limits are Linux's")
def test_bad_programs_are_stopped_and_reported_and_the_good_team_is_unaffected(
    tmp_path: Path,
) -> None:
    teams = {
        "Good": GOOD,
        "Bomb": FORK_BOMB,
        "Hog": MEMORY_HOG,
        "Filler": DISK_FILLER,
        "Loop": LOOP,
        "Flood": FLOOD,
        "Endless": ENDLESS_LINE,
        "Opener": OPENER,
        "Spy": SPY.replace(
            "TARGET", repr(str(tmp_path / "course" / "teams" / "good" / "robot.py"))
        ),
    }
    spec = load_grading(
        grading_folder(tmp_path / "course", LIMITS, teams, targets=("B1",), wall=30, seconds=60)
    )
    pools: list[Any] = []
    run_grading(spec, tmp_path / "all", engine=_tracked_pool(2, pools), workers=2)
    alone = spec.only(tmp_path / "course" / "teams" / "good")
    run_grading(alone, tmp_path / "alone", engine=_tracked_pool(1, pools), workers=1)
    left = [pid for pid in descendants() if "robot.py" in _command(pid)]
    # no process of theirs left (the forkserver stays, as it does for sweeps)
    assert left == [], [(_command(pid), _state(pid)) for pid in left]
    assert pools
    assert _box_users(pools) == []  # nor anywhere else, however it detached

    rows = _rows(tmp_path / "all" / "results.csv")
    by_team: dict[str, list[dict[str, str]]] = {}
    for r in rows:
        by_team.setdefault(r["team"], []).append(r)
    log = {(r["team"], r["violation"]) for r in _rows(tmp_path / "all" / "violations.csv")}
    # the fork bomb: forks refused at 16 processes of its box
    for r in by_team["Bomb"]:
        assert (r["status"], r["exit_status"]) == ("error", "3")
        assert "fork refused: [Errno 11] Resource temporarily unavailable" in r["detail"]
    assert ("Bomb", "process-limit") in log
    # the memory hog: MemoryError at 400 MB
    assert all(r["status"] == "error" and "MemoryError" in r["detail"] for r in by_team["Hog"])
    assert ("Hog", "memory-limit") in log
    # the disk filler: stopped at 8 MB by the file-size limit, in its own copy of its folder
    assert all(
        r["status"] == "error" and "File too large" in r["detail"] for r in by_team["Filler"]
    )
    assert ("Filler", "file-size-limit") in log
    assert not (tmp_path / "course" / "teams" / "filler" / "fill.bin").exists()
    # the infinite loop: SIGXCPU after 3 CPU seconds
    assert all(r["exit_status"] == "-24" for r in by_team["Loop"])
    assert ("Loop", "cpu-limit") in log
    # the spy: refused by Landlock, the other team's file never printed
    for r in by_team["Spy"]:
        assert r["status"] == "error"
        assert "PermissionError" in r["detail"]
        assert "Permission denied" in r["detail"]
        assert "team writes it" not in r["detail"]
    assert ("Spy", "refused-access") in log
    # the flood: every message costs the link's simulated time, so it ends at the grading's
    # simulated-time limit (60 s, a message a step); its unread replies wait in its socket
    for r in by_team["Flood"]:
        assert r["status"] == "seconds"
        assert r["messages"] == str(60 * 60)
    assert ("Flood", "time-limit") in log
    # the endless line: refused at 64 KiB (MAX_MESSAGE_BYTES), its connection closed
    for r in by_team["Endless"]:
        assert (r["status"], r["over_limit"], r["messages"]) == ("error", "1", "0")
    assert ("Endless", "message-limit") in log
    # connections without end: stopped at its box's 64 open files
    for r in by_team["Opener"]:
        assert r["status"] == "error"
        assert "Too many open files" in r["detail"]
    assert ("Opener", "open-files-limit") in log
    # the good team: its numbers are those it gets graded alone
    alone_rows = _rows(tmp_path / "alone" / "results.csv")
    skip = {"wall_time"}
    assert [{k: v for k, v in r.items() if k not in skip} for r in by_team["Good"]] == [
        {k: v for k, v in r.items() if k not in skip} for r in alone_rows
    ]
    assert all(r["delivered"] == "True" for r in by_team["Good"])
    board = _rows(tmp_path / "all" / "leaderboard.csv")
    assert board[0]["team"] == "Good"


LANDLOCK_CREATE_RULESET = 444
"""The system call's number on x86-64 and on arm64 (the generic table)."""


def _landlock_abi() -> int:
    """The kernel's Landlock ABI (0: none, or a machine whose call number is not known here)."""
    import ctypes
    import platform

    if not sys.platform.startswith("linux") or platform.machine() not in ("x86_64", "aarch64"):
        return 0
    libc = ctypes.CDLL(None, use_errno=True)
    libc.syscall.restype = ctypes.c_long
    version = ctypes.c_uint32(1)  # LANDLOCK_CREATE_RULESET_VERSION
    return max(int(libc.syscall(LANDLOCK_CREATE_RULESET, None, ctypes.c_size_t(0), version)), 0)


CALLER = """import socket
try:
    socket.create_connection(("127.0.0.1", OUTSIDE), timeout=10).close()
    called = "connected"
except OSError as exc:
    called = f"refused: {exc!r}"
"""


@pytest.mark.slow
@pytest.mark.timeout(600)
@pytest.mark.parametrize("landlock", [True, False])
def test_the_box_lets_a_program_connect_to_its_run_s_ports_only(
    tmp_path: Path, landlock: bool
) -> None:
    """The team's program calls a port outside its run (the test's own listener), then does
    its delivery through its run's ports: refused and delivered in its box, by Landlock alone
    (``network = false``), or by its network namespace alone (``landlock = false``: nothing
    listens at that port in its own network). Without either the call gets through:
    ``test_a_boxed_program_s_network_holds_the_simulator_s_ports_only``."""
    import socket

    if landlock and _landlock_abi() < 4:
        pytest.skip(
            f"Landlock's TCP rules need ABI 4 (Linux 6.7); this machine has {_landlock_abi()}"
        )
    if not landlock and unavailable():
        pytest.skip(f"no network namespaces here: {unavailable()}")
    with socket.create_server(("127.0.0.1", 0)) as outside:
        port = outside.getsockname()[1]
        program = CALLER.replace("OUTSIDE", str(port)) + GOOD.replace(
            "    main()\n", '    main()\n    raise SystemExit(f"the outside call: {called}")\n'
        )
        on, off = ("landlock", "network") if landlock else ("network", "landlock")
        extra = f"[limits]\n{on} = true\n{off} = false"
        spec = load_grading(
            grading_folder(tmp_path / "course", extra, {"Caller": program}, targets=("B1",))
        )
        run_grading(spec, tmp_path / "out", engine=local_pool(1), workers=1)
        outside.setblocking(False)
        try:
            outside.accept()[0].close()
            reached = True
        except BlockingIOError:
            reached = False
    (r,) = _rows(tmp_path / "out" / "results.csv")
    assert r["delivered"] == "True"  # its own run's ports: allowed
    assert r["status"] == "error"
    assert not reached
    if landlock:
        assert "the outside call: refused: PermissionError(13, 'Permission denied')" in r["detail"]
    else:
        refused = "the outside call: refused: ConnectionRefusedError(111, 'Connection refused')"
        assert refused in r["detail"]


REACHER = """import errno, os, socket, sys
def call(address, kind=socket.SOCK_STREAM):
    try:
        with socket.socket(socket.AF_INET, kind) as s:
            s.settimeout(5)
            if kind == socket.SOCK_DGRAM:
                s.sendto(b"hello", address)
                return "sent"
            s.connect(address)
            return "connected"
    except OSError as exc:
        return errno.errorcode.get(exc.errno, str(exc))
print("simulator", call(("127.0.0.1", int(sys.argv[1]))))
print("outside", call(("127.0.0.1", int(sys.argv[2]))))
print("external", call(("192.0.2.1", 80)))
print("udp", call(("192.0.2.1", 53), socket.SOCK_DGRAM))
"""


@pytest.mark.skipif(bool(unavailable()), reason=f"no network namespaces here: {unavailable()}")
@pytest.mark.parametrize("network", [True, False])
def test_a_boxed_program_s_network_holds_the_simulator_s_ports_only(
    tmp_path: Path, network: bool
) -> None:
    """A boxed program (Landlock off, so the refusals are the namespace's) reaches the run's
    listener, which the namespace's helper opened and this process accepts on; a listener of
    this machine outside the box, an address beyond it and a UDP datagram do not get out.
    Without the namespace the same calls get through."""
    import socket

    from grade_support import PYTHON
    from simmer.lockstep import Program
    from simmer.lockstep.box import Box, BoxLimits, make_box
    from simmer.lockstep.netns import Network

    team = tmp_path / "team"
    team.mkdir()
    (team / "reach.py").write_text(REACHER, encoding="utf-8")
    limits = BoxLimits(landlock=False, network=network)
    opened = Network.open("127.0.0.1", [0]) if network else None
    assert not isinstance(opened, str)
    with (
        tempfile.TemporaryDirectory(prefix="simmer-run-") as scratch,  # as a grading's run
        socket.create_server(("127.0.0.1", 0)) as outside,
    ):
        box = Box(limits, *make_box(team, Path(scratch)), opened)
        simulator = opened.listeners[0] if opened else socket.create_server(("127.0.0.1", 0))
        ports = [simulator.getsockname()[1], outside.getsockname()[1]]
        read, write = os.pipe()
        program = Program.start(
            [PYTHON, "reach.py", *map(str, ports)], dict(os.environ), box=box, ports=ports,
            output=write,
        )  # fmt: skip
        os.close(write)
        status = program.wait(30)
        with os.fdopen(read) as printed:
            text = printed.read()
        assert status == 0, text
        said = dict(line.split() for line in text.splitlines())
        simulator.settimeout(5)
        simulator.accept()[0].close()  # the program's call arrived here, in its namespace
        simulator.close()
        if opened:
            opened.close()
    assert said["simulator"] == "connected"
    if network:
        assert said == {
            "simulator": "connected",
            "outside": "ECONNREFUSED",  # nothing listens there in its namespace
            "external": "ENETUNREACH",
            "udp": "ENETUNREACH",
        }
    else:
        assert said["outside"] == "connected"
        assert said["udp"] == "sent"


@pytest.mark.skipif(bool(unavailable()), reason=f"no network namespaces here: {unavailable()}")
def test_a_network_that_cannot_be_made_says_why_and_leaves_nothing_open() -> None:
    """An address the namespace's loopback does not have: one line saying why (what a run
    then writes in its output, going on in the machine's network), no descriptor kept."""
    from simmer.lockstep.netns import Network

    before = set(os.listdir("/proc/self/fd"))
    said = Network.open("192.0.2.7", [0, 0, 0])
    assert isinstance(said, str)
    assert said.startswith(
        "cannot make a network namespace here: [Errno 99] Cannot assign requested address"
    )
    assert set(os.listdir("/proc/self/fd")) <= before


NOTE_PROBE = """import sys
from simmer.grade import load_grading
from simmer.grade.engine import box_notes
print("\\n".join(box_notes(load_grading(sys.argv[1]))))
"""


@pytest.mark.slow  # a Python importing simmer.grade: 1.2 CPU s
@pytest.mark.skipif(
    bool(unavailable()) or not shutil.which("unshare"),
    reason="needs namespaces and util-linux's unshare to make a machine that forbids them",
)
def test_a_grading_where_namespaces_are_forbidden_says_so_in_one_line(tmp_path: Path) -> None:
    """Inside a user namespace whose ``max_net_namespaces`` is 0 (a machine that forbids
    them, made for this test alone), the grading's note says why the box has no network of
    its own; outside it, and with ``network = false``, there is no note."""
    import subprocess

    grading = grading_folder(tmp_path, "", {"Good": GOOD}, targets=("B1",))
    probe = tmp_path / "probe.py"
    probe.write_text(NOTE_PROBE, encoding="utf-8")
    forbid = 'echo 0 > /proc/sys/user/max_net_namespaces && exec "$0" "$@"'
    said = subprocess.run(
        ["unshare", "-r", "sh", "-c", forbid, sys.executable, str(probe), str(grading)],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    ).stdout
    assert said.startswith(
        "the box: no network of its own for each program here (cannot make a network "
        "namespace here: [Errno 28] unshare: No space left on device); programs share this "
        "machine's network"
    )
    from simmer.grade.engine import box_notes

    assert box_notes(load_grading(grading)) == ()
    off = grading_folder(tmp_path / "off", "[limits]\nnetwork = false", {"Good": GOOD})
    assert box_notes(load_grading(off)) == ()
