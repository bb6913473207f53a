"""A network of a boxed program's own (Linux network namespaces): the program reaches the
simulator on loopback and nothing else, no other port of this machine, no other machine.

In a fresh network namespace loopback is the namespace's own, so the simulator's ports must
be there too. :meth:`Network.open` runs this file as a small helper process (standard
library only): it makes a namespace (as root a network namespace; otherwise a user namespace
with the network namespace in it, which Linux lets any user make unless the machine forbids
it), brings its loopback up, opens the run's listening sockets in it and hands them, and the
namespaces themselves, back over a Unix socket (``SCM_RIGHTS``), then exits. The simulator
accepts on those sockets as on its own (a socket stays in the namespace it was made in,
whoever holds it: no copying between the two, so a run is the same as without the box), and
the launcher (:mod:`simmer.lockstep.boxlaunch`) joins the namespaces before it becomes the
program. Where it cannot be done (not Linux, namespaces forbidden) :meth:`Network.open`
says why in one line and the run goes on with the machine's network (Landlock's port rules
still confine TCP where the kernel has them).
"""

from __future__ import annotations

import contextlib
import ctypes
import fcntl
import os
import socket
import struct
import sys

CLONE_NEWUSER = 0x10000000
CLONE_NEWNET = 0x40000000
SIOCGIFFLAGS, SIOCSIFFLAGS, IFF_UP = 0x8913, 0x8914, 0x1
HELPER_SECONDS = 10.0
"""Wall seconds the helper may take to make the namespace (0.07 s here, half of it starting
Python: this file imports only what the helper needs, no dataclasses, no subprocess)."""


class Network:
    """A network namespace of one run: listening sockets in it (in the order asked) and the
    namespaces to join, as file descriptors (the user namespace's first, where there is one),
    ``kinds`` saying which (``user``, ``net``)."""

    def __init__(
        self, listeners: list[socket.socket], namespaces: list[int], kinds: list[str]
    ) -> None:
        self.listeners = listeners
        self.namespaces = namespaces
        self.kinds = kinds

    @classmethod
    def open(cls, host: str, ports: list[int]) -> Network | str:
        """A namespace with a listener on ``host`` at each of ``ports`` (0: a free one in
        it); or, where the machine cannot make one, a line saying why."""
        if not sys.platform.startswith("linux"):
            return f"no network namespaces on {sys.platform} (Linux only)"
        import subprocess

        mine, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        with mine, theirs:
            args = [sys.executable, "-I", __file__, str(theirs.fileno()), host]
            try:
                helper = subprocess.Popen(
                    [*args, *map(str, ports)],
                    pass_fds=[theirs.fileno()],
                    stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                )
            except OSError as exc:
                return f"cannot start the network namespace's helper: {exc}"
            theirs.close()
            mine.settimeout(HELPER_SECONDS)
            try:
                data, fds, _flags, _address = socket.recv_fds(mine, 4096, len(ports) + 2)
                message = data.decode(errors="replace")
            except OSError as exc:
                message = (
                    f"its helper did not answer within {HELPER_SECONDS:g} s (HELPER_SECONDS): {exc}"
                )
                fds = []
            finally:
                try:
                    helper.wait(HELPER_SECONDS)
                except subprocess.TimeoutExpired:
                    helper.kill()
                    helper.wait()
        text = message
        if not text.startswith("ok ") or len(fds) < len(ports) + 1:
            for fd in fds:
                os.close(fd)
            return text or "the network namespace's helper ended without a word"
        kinds = text.split()[1:]
        listeners = [socket.socket(fileno=fd) for fd in fds[: len(ports)]]
        return cls(listeners, fds[len(ports) :], kinds)

    def close(self) -> None:
        """Close the namespaces' descriptors and the listeners (the servers close them too,
        when they took them; closing one twice is nothing)."""
        for fd in self.namespaces:
            with contextlib.suppress(OSError):
                os.close(fd)
        self.namespaces = []
        for listener in self.listeners:
            listener.close()


def unavailable() -> str:
    """Why this machine cannot give a boxed program a network of its own ('' if it can):
    tried once, as a run would."""
    opened = Network.open("127.0.0.1", [])
    if isinstance(opened, str):
        return opened
    opened.close()
    return ""


def _helper(argv: list[str]) -> None:
    """The helper process: make the namespace, bring up its loopback, listen, hand back."""
    channel = socket.socket(fileno=int(argv[1]))
    host, ports = argv[2], [int(port) for port in argv[3:]]
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        uid, gid = os.geteuid(), os.getegid()
        flags = CLONE_NEWNET if uid == 0 else CLONE_NEWUSER | CLONE_NEWNET
        if libc.unshare(flags) != 0:
            error = ctypes.get_errno()
            raise OSError(error, f"unshare: {os.strerror(error)}")
        kinds = ["net"]
        if uid != 0:
            kinds.insert(0, "user")
            for name, text in (("setgroups", "deny"), ("uid_map", f"{uid} {uid} 1")):
                with open(f"/proc/self/{name}", "w") as file:
                    file.write(text)
            with open("/proc/self/gid_map", "w") as file:
                file.write(f"{gid} {gid} 1")
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as control:
            request = struct.pack("16sH14x", b"lo", 0)
            flags_now = struct.unpack("16sH14x", fcntl.ioctl(control, SIOCGIFFLAGS, request))[1]
            fcntl.ioctl(control, SIOCSIFFLAGS, struct.pack("16sH14x", b"lo", flags_now | IFF_UP))
        listeners = [socket.create_server((host, port), backlog=128) for port in ports]
        spaces = [os.open(f"/proc/self/ns/{kind}", os.O_RDONLY) for kind in kinds]
        fds = [sock.fileno() for sock in listeners] + spaces
        socket.send_fds(channel, [("ok " + " ".join(kinds)).encode()], fds)
    except OSError as exc:
        channel.sendall(f"cannot make a network namespace here: {exc}".encode())


if __name__ == "__main__":
    _helper(sys.argv)
