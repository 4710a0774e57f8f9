"""A student's server in a network namespace of its own, joined to the machine's loopback by a relay.

Every student's kernels, terminals and their own programs then live on a loopback of their own: no other student
can list their kernels' ports (``/proc/net/tcp``), subscribe to a kernel's IOPub socket and read its code and
output, or reach an abstract unix socket of theirs; and they reach nothing outside either. The server itself must
still be reached by the hub and its proxy, and must reach the hub's API (to check who may use it, to report
activity). :func:`start`, called as root by the sandbox's init before it starts the server:

1. listens on the server's address (``127.0.0.1:<port>`` the hub chose) in the machine's namespace;
2. moves the calling process into a new network namespace and brings its loopback up (the server, a child started
   after this, is born there);
3. listens there on the hub API's address (``127.0.0.1:<hub port>``);
4. relays each connection to the other side, with two threads: one in the new namespace (accepting the hub's and
   the proxy's connections, opening the matching one to the server), one moved back into the machine's namespace
   (accepting the server's connections to the hub, opening the matching one to the hub).

Only bytes pass; nothing is read or changed. The relay keeps no state of its own beyond the open connections.
"""

from __future__ import annotations

import ctypes
import fcntl
import os
import socket
import struct
import threading
import time

__all__ = ["start", "Relay", "loopback_up"]

_LIBC = ctypes.CDLL(None, use_errno=True)
CLONE_NEWNET = 0x40000000
SIOCGIFFLAGS, SIOCSIFFLAGS, IFF_UP = 0x8913, 0x8914, 0x1
CONNECT_WAIT_S = 10.0
"""How long a connection to the server waits for it to listen (the hub asks before the server is up)."""


def _check(ret: int, what: str) -> None:
    if ret != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"{what}: {os.strerror(err)}")


def loopback_up() -> None:
    """Bring the calling thread's network namespace's ``lo`` up (a new namespace's is down)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        req = struct.pack("16sh14x", b"lo", 0)
        flags = struct.unpack("16sh14x", fcntl.ioctl(s.fileno(), SIOCGIFFLAGS, req))[1]
        fcntl.ioctl(s.fileno(), SIOCSIFFLAGS, struct.pack("16sh14x", b"lo", flags | IFF_UP))


def _listen(host: str, port: int) -> socket.socket:
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind((host, port))
    s.listen(128)
    return s


def _pump(src: socket.socket, dst: socket.socket, done: threading.Event) -> None:
    """Copy ``src`` to ``dst`` until ``src`` ends; then end ``dst``'s writing side (both closed by the last)."""
    try:
        while True:
            data = src.recv(65536)
            if not data:
                break
            dst.sendall(data)
    except OSError:
        pass
    finally:
        try:
            dst.shutdown(socket.SHUT_WR)
        except OSError:
            pass
        if done.is_set():
            src.close()
            dst.close()
        else:
            done.set()


def _connect(address, wait_s: float) -> socket.socket | None:
    deadline = time.monotonic() + wait_s
    while True:
        try:
            return socket.create_connection(address, timeout=5)
        except OSError:
            if time.monotonic() > deadline:
                return None
            time.sleep(0.1)


class Relay:
    """The relay's two listeners and threads (:func:`start`); ``stop()`` closes the listeners."""

    def __init__(self):
        self.listeners: list[socket.socket] = []
        self.stopped = threading.Event()

    def serve(self, listener: socket.socket, address, wait_s: float, netns_fd: int | None = None,
              ready: threading.Event | None = None) -> None:
        """Accept on ``listener``; for each connection, open one to ``address`` and pump both ways. With
        ``netns_fd``, this thread first moves into that network namespace (new connections are opened there)."""
        try:
            if netns_fd is not None:
                _check(_LIBC.setns(netns_fd, CLONE_NEWNET), "setns")
        finally:
            if ready is not None:
                ready.set()
        while not self.stopped.is_set():
            try:
                conn, _ = listener.accept()
            except OSError:
                if self.stopped.is_set():
                    return
                time.sleep(0.05)
                continue
            threading.Thread(target=self._pair, args=(conn, address, wait_s), daemon=True).start()

    @staticmethod
    def _pair(conn: socket.socket, address, wait_s: float) -> None:
        other = _connect(address, wait_s)
        if other is None:
            conn.close()
            return
        other.settimeout(None)
        for s in (conn, other):
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        done = threading.Event()
        threading.Thread(target=_pump, args=(other, conn, done), daemon=True).start()
        _pump(conn, other, done)

    def stop(self) -> None:
        self.stopped.set()
        for s in self.listeners:
            try:
                s.close()
            except OSError:
                pass


def start(spec) -> Relay:
    """Steps 1-4 of the module docstring. ``spec``: ``{"server": [host, port], "hub": [host, port]}``.

    Must be called as root, in the machine's network namespace, before the server is started; returns with the
    calling process in the new namespace."""
    server = (spec["server"][0], int(spec["server"][1]))
    hub = (spec["hub"][0], int(spec["hub"][1]))
    relay = Relay()
    outside = _listen(*server)  # 1: where the hub and the proxy connect
    host_ns = os.open("/proc/self/ns/net", os.O_RDONLY)
    _check(_LIBC.unshare(CLONE_NEWNET), "unshare(CLONE_NEWNET)")  # 2
    loopback_up()
    inside = _listen(*hub)  # 3: where the server connects to the hub
    relay.listeners = [outside, inside]
    threading.Thread(target=relay.serve, args=(outside, server, CONNECT_WAIT_S), daemon=True).start()
    ready = threading.Event()
    threading.Thread(target=relay.serve, args=(inside, hub, 0.0, host_ns, ready), daemon=True).start()
    ready.wait(10)
    os.close(host_ns)
    return relay
