"""Starts a graded program inside its box, then becomes it (``exec``): run as
``python -I boxlaunch.py SETTINGS -- PROGRAM ARGS...`` by :mod:`simmer.lockstep.box`.

Standard library only, and imports nothing of SimMeR's: it runs in a fresh interpreter
between the worker's fork and the program, so it must start in milliseconds. In order:

1. as root (a TA's server, a container), the box's folder is given to a user id of the box's
   own and the process becomes that user, so the process limit counts this box's processes
   only (Linux never limits root's);
2. the resource limits (CPU seconds, address space, file size, processes, open files);
3. Linux Landlock (kernel 5.13 and later, no privilege needed): the files it may read are
   the system's, the Python installations' and SimMeR's; it may write in its box only; with
   Landlock's network rules (kernel 6.7 and later) it may open TCP connections to this run's
   ports only, and bind none; with its scopes (6.12) it may not signal processes outside its
   box. An older kernel applies what it has, and ``box.json`` in the box says what was.

Before them all, it joins the run's network namespace where it has one (Linux), holding
only the simulator's ports (:mod:`simmer.lockstep.netns`).

Any failure of a step that the kernel does not offer is recorded and the program still runs;
a failure of a step it offers stops the launch (exit status 125, a line on standard error).
"""

import ctypes
import json
import os
import sys
from typing import Any, NoReturn

try:  # here, before the box's user may be unable to read this Python's modules
    import resource
except ImportError:  # Windows
    resource = None  # type: ignore[assignment]

EXIT_BOX = 125
"""Exit status when the box could not be set up as asked."""

_FS_EXECUTE = 1 << 0
_FS_WRITE_FILE = 1 << 1
_FS_READ_FILE = 1 << 2
_FS_READ_DIR = 1 << 3
_FS_REMOVE_DIR = 1 << 4
_FS_REMOVE_FILE = 1 << 5
_FS_MAKE_CHAR = 1 << 6
_FS_MAKE_DIR = 1 << 7
_FS_MAKE_REG = 1 << 8
_FS_MAKE_SOCK = 1 << 9
_FS_MAKE_FIFO = 1 << 10
_FS_MAKE_BLOCK = 1 << 11
_FS_MAKE_SYM = 1 << 12
_FS_REFER = 1 << 13
_FS_TRUNCATE = 1 << 14
_NET_BIND_TCP = 1 << 0
_NET_CONNECT_TCP = 1 << 1
_SCOPE_ABSTRACT_UNIX = 1 << 0
_SCOPE_SIGNAL = 1 << 1
_CREATE_RULESET, _ADD_RULE, _RESTRICT_SELF = 444, 445, 446  # every architecture's numbers
_VERSION = 1
_RULE_PATH_BENEATH, _RULE_NET_PORT = 1, 2
_PR_SET_NO_NEW_PRIVS = 38
_CLONE_NEWUSER, _CLONE_NEWNET = 0x10000000, 0x40000000


class _PathBeneath(ctypes.Structure):
    _pack_ = 1
    _fields_ = [("allowed_access", ctypes.c_uint64), ("parent_fd", ctypes.c_int32)]


class _NetPort(ctypes.Structure):
    _fields_ = [("allowed_access", ctypes.c_uint64), ("port", ctypes.c_uint64)]


class _Ruleset(ctypes.Structure):
    _fields_ = [
        ("handled_access_fs", ctypes.c_uint64),
        ("handled_access_net", ctypes.c_uint64),
        ("scoped", ctypes.c_uint64),
    ]


def _fail(text: str) -> NoReturn:
    sys.stderr.write(f"SimMeR box: {text}\n")
    sys.stderr.flush()
    os._exit(EXIT_BOX)


def _join_network(settings: dict[str, Any], done: list[str]) -> None:
    """Join the run's network namespace (:mod:`simmer.lockstep.netns`): the user namespace
    that owns it first, where there is one (not as root)."""
    spaces = settings.get("namespaces")
    if not spaces:
        return
    libc = ctypes.CDLL(None, use_errno=True)
    for kind, flag in (("user", _CLONE_NEWUSER), ("net", _CLONE_NEWNET)):
        fd = spaces.get(kind)
        if fd is None:
            continue
        if libc.setns(fd, flag) != 0:
            _fail(f"cannot join the box's {kind} namespace (errno {ctypes.get_errno()})")
        os.close(fd)
    done.append("network namespace")


def _become_box_user(settings: dict[str, Any], done: list[str]) -> None:
    """As root: hand the box to the box's own user id and become it."""
    uid = settings.get("uid")
    if uid is None or os.getuid() != 0:
        return
    for top in (settings["folder"], settings.get("tmp")):
        if not top:
            continue
        os.chown(top, uid, uid)
        for root, dirs, files in os.walk(top):
            for name in dirs + files:
                os.chown(os.path.join(root, name), uid, uid, follow_symlinks=False)
    os.setgroups([])
    os.setgid(uid)
    os.setuid(uid)
    done.append(f"user {uid}")


def _limit(settings: dict[str, Any], done: list[str]) -> None:
    """The resource limits (each where the system has it)."""
    if resource is None:
        if os.name == "posix":
            _fail("the resource module is missing: the limits cannot be set")
        return  # Windows has no resource limits
    names = {
        "cpu_seconds": ("RLIMIT_CPU", 1),
        "memory_mb": ("RLIMIT_AS", 1 << 20),
        "file_mb": ("RLIMIT_FSIZE", 1 << 20),
        "processes": ("RLIMIT_NPROC", 1),
        "open_files": ("RLIMIT_NOFILE", 1),
    }
    for key, (name, scale) in sorted(names.items()):
        value = settings.get(key)
        number = getattr(resource, name, None)
        if value is None or number is None:
            continue
        amount = int(value * scale)
        if key == "processes" and os.getuid() != 0:
            amount += _my_processes()  # counted over the user's processes, not the box's
        hard = amount + 1 if key == "cpu_seconds" else amount  # SIGXCPU, then SIGKILL
        try:
            resource.setrlimit(number, (amount, hard))
        except (ValueError, OSError) as exc:
            _fail(f"cannot set {name} to {amount}: {exc}")
        done.append(key)


def _my_processes() -> int:
    """The processes of this user now (Linux: from /proc; elsewhere 0)."""
    uid = os.getuid()
    count = 0
    try:
        entries = os.listdir("/proc")
    except OSError:
        return 0
    for entry in entries:
        if entry.isdigit():
            try:
                if os.stat("/proc/" + entry).st_uid == uid:
                    count += 1
            except OSError:
                pass
    return count


def _landlock(settings: dict[str, Any], done: list[str]) -> None:
    """Confine files (and, where the kernel can, TCP ports and signals) with Landlock."""
    if not sys.platform.startswith("linux"):
        return
    libc = ctypes.CDLL(None, use_errno=True)
    syscall = libc.syscall
    syscall.restype = ctypes.c_long
    abi = syscall(_CREATE_RULESET, None, ctypes.c_size_t(0), ctypes.c_uint32(_VERSION))
    if abi < 1:
        return  # no Landlock in this kernel: recorded by its absence in box.json
    read = _FS_EXECUTE | _FS_READ_FILE | _FS_READ_DIR
    every = read | _FS_WRITE_FILE | _FS_REMOVE_DIR | _FS_REMOVE_FILE | _FS_MAKE_CHAR
    every |= _FS_MAKE_DIR | _FS_MAKE_REG | _FS_MAKE_SOCK | _FS_MAKE_FIFO | _FS_MAKE_BLOCK
    every |= _FS_MAKE_SYM
    if abi >= 2:
        every |= _FS_REFER
    if abi >= 3:
        every |= _FS_TRUNCATE
    attr = _Ruleset(every, 0, 0)
    size = 8
    if abi >= 4:
        attr.handled_access_net = _NET_BIND_TCP | _NET_CONNECT_TCP
        size = 16
    if abi >= 6:
        attr.scoped = _SCOPE_ABSTRACT_UNIX | _SCOPE_SIGNAL
        size = 24
    ruleset = syscall(_CREATE_RULESET, ctypes.byref(attr), ctypes.c_size_t(size), 0)
    if ruleset < 0:
        _fail(f"cannot make a Landlock ruleset (errno {ctypes.get_errno()})")
    writable = every & ~(_FS_MAKE_CHAR | _FS_MAKE_BLOCK)
    rules = [(path, read) for path in settings.get("read", [])]
    rules += [(path, writable) for path in settings.get("write", [])]
    rules += [(path, _FS_READ_FILE | _FS_WRITE_FILE) for path in settings.get("devices", [])]
    for path, wanted in rules:
        access = wanted
        try:
            fd = os.open(path, os.O_PATH | os.O_CLOEXEC)
        except OSError:
            continue  # not on this system
        if not os.path.isdir(path):
            access &= _FS_EXECUTE | _FS_READ_FILE | _FS_WRITE_FILE | _FS_TRUNCATE
        rule = _PathBeneath(access & every, fd)
        if syscall(_ADD_RULE, ruleset, _RULE_PATH_BENEATH, ctypes.byref(rule), 0) != 0:
            _fail(f"cannot allow {path} in the box (errno {ctypes.get_errno()})")
        os.close(fd)
    if abi >= 4:
        for port in settings.get("ports", []):
            port_rule = _NetPort(_NET_CONNECT_TCP, port)
            if syscall(_ADD_RULE, ruleset, _RULE_NET_PORT, ctypes.byref(port_rule), 0) != 0:
                _fail(f"cannot allow port {port} in the box (errno {ctypes.get_errno()})")
    if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        _fail(f"cannot set no_new_privs (errno {ctypes.get_errno()})")
    if syscall(_RESTRICT_SELF, ruleset, 0) != 0:
        _fail(f"cannot enter the Landlock domain (errno {ctypes.get_errno()})")
    os.close(ruleset)
    done.append(f"landlock files (ABI {abi})")
    if abi >= 4:
        done.append("landlock tcp ports")
    if abi >= 6:
        done.append("landlock signals")


def main(argv: list[str]) -> None:
    """Set the box up as ``argv[1]`` (JSON) says, then run ``argv[3:]`` in this process."""
    if len(argv) < 4 or argv[2] != "--":
        _fail("usage: boxlaunch.py SETTINGS -- PROGRAM ARGS...")
    settings = json.loads(argv[1])
    program = argv[3:]
    done: list[str] = []
    _join_network(settings, done)
    _become_box_user(settings, done)
    _limit(settings, done)
    if settings.get("landlock", True):
        _landlock(settings, done)
    report = settings.get("report")
    if report:
        try:
            with open(report, "w") as file:
                json.dump({"enforced": done}, file)
        except OSError:
            pass
    try:
        os.execve(program[0], program, os.environ)
    except OSError as exc:
        hint = ""
        if "uid" in settings and os.getuid() == settings["uid"]:
            hint = (
                f"; the box runs as user {settings['uid']}, not root: name an interpreter every "
                "user may run (/usr/bin/python3, not one in root's home)"
            )
        _fail(f"cannot start {program[0]}: {exc}{hint}")


if __name__ == "__main__":
    main(sys.argv)
