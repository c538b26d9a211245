"""Connections that are still introducing themselves, bounded in number and in time.

A peer that opens a connection and sends a byte at a time (slowloris) must not hold a
server's threads: per-``recv`` timeouts never fire while bytes trickle in. Every server
socket of hetros's ROS 1 side (the master's and the nodes' XML-RPC, TCPROS and ROSRPC)
admits connections through one of these: a connection has ``patience`` seconds to finish
its request or header, and when ``limit`` are still at it, the one that has been at it
longest is closed to make room. A well-behaved client finishes within a millisecond, so
it is never the oldest: good calls are served while slow ones are cut off.
"""

from __future__ import annotations

import socket
import threading
import time
from collections import OrderedDict

from ..._log import get_logger

log = get_logger("hetros.ros1")

SWEEP_EVERY = 0.5


class Admission:
    """The connections of one server still introducing themselves."""

    def __init__(self, what: str, limit: int, patience: float) -> None:
        self.what = what
        self.limit = limit
        self.patience = patience
        self._lock = threading.Lock()
        self._pending: OrderedDict[socket.socket, float] = OrderedDict()
        self._sweeper: threading.Thread | None = None
        self._closed = False
        self.cut = 0  # connections closed for taking too long or for room

    def enter(self, sock: socket.socket, peer: str) -> None:
        """Admit ``sock``; the oldest pending connection is cut when ``limit`` are pending."""
        with self._lock:
            self._pending[sock] = time.monotonic()
            evicted = self._pending.popitem(last=False)[0] if len(self._pending) > self.limit else None
            if self._sweeper is None:
                self._sweeper = threading.Thread(target=self._sweep, name="hetros-ros1-admission", daemon=True)
                self._sweeper.start()
        if evicted is not None:
            self._cut(evicted, f"{self.limit} connections were still introducing themselves; closed the "
                               f"oldest to admit {peer}")

    def leave(self, sock: socket.socket) -> None:
        """``sock`` finished its request or header (or ended): it no longer counts."""
        with self._lock:
            self._pending.pop(sock, None)

    def _sweep(self) -> None:
        while not self._closed:
            time.sleep(SWEEP_EVERY)
            now = time.monotonic()
            with self._lock:
                late = [sock for sock, since in self._pending.items() if now - since > self.patience]
                for sock in late:
                    del self._pending[sock]
            for sock in late:
                self._cut(sock, f"a connection did not finish its request within {self.patience:g} s")

    def _cut(self, sock: socket.socket, why: str) -> None:
        self.cut += 1
        log.warning("%s: %s", self.what, why)
        try:
            sock.shutdown(socket.SHUT_RDWR)  # the thread reading it sees the end and lets go
        except OSError:
            pass

    def close(self) -> None:
        self._closed = True
