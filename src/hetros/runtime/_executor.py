"""The per-node callback queue (ROS-lite): a node's callbacks never run concurrently.

One wait per node. A node whose readers include shared-memory ones owns a wake
channel (an iceoryx2 event service): publishers in other processes notify it
with the reader's event id, in-process notifications interrupt it, and exactly
one thread at a time blocks on it (without the GIL). Other threads that wait
for the same node at that moment (a ``take`` in a second thread, a service
call from inside a callback) wait on a condition that the blocked thread
signals after every wake-up. A node without shared-memory readers waits on
that condition alone. No helper thread stands between a transport and a
callback, and an idle node uses no CPU.
"""

from __future__ import annotations

import heapq
import itertools
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Protocol


class Dispatchable(Protocol):
    def dispatch(self) -> bool:
        """Run one callback if there is work; return whether more work may be pending."""
        ...


class WaitSource(Protocol):
    """What a node can block on besides its condition: the shm transport's wake channel."""

    def wait(self, timeout: float | None) -> None:
        """Block until an event or ``timeout``, then run the wake function of each reader that fired."""
        ...

    def interrupt(self) -> None:
        """Make a blocked ``wait`` return (from any thread)."""
        ...


class Executor:
    def __init__(self, stop: threading.Event, source: WaitSource | None = None) -> None:
        self._stop = stop
        self._source = source
        self._cond = threading.Condition()
        self._generation = 0
        self._listening = False
        self._listener: int | None = None
        self._ready: deque[Dispatchable] = deque()
        self._queued: set[int] = set()
        self._timers: list[tuple[float, int, Callable[[], float | None]]] = []
        self._counter = itertools.count()
        self.entities = 0

    @property
    def generation(self) -> int:
        """Changes whenever something may have become ready; pass it to :meth:`wait`."""
        return self._generation

    def notify(self, entity: Dispatchable) -> None:
        """Mark ``entity`` as having work (callable from any thread)."""
        with self._cond:
            key = id(entity)
            if key not in self._queued:
                self._queued.add(key)
                self._ready.append(entity)
        self.wake()

    def wake(self) -> None:
        """Something may be ready: every waiter rechecks (callable from any thread)."""
        with self._cond:
            self._generation += 1
            self._cond.notify_all()
            interrupt = self._listening and self._listener != threading.get_ident()
        if interrupt and self._source is not None:
            self._source.interrupt()

    def wait(self, seen: int, timeout: float | None) -> None:
        """Block until the generation differs from ``seen`` or ``timeout`` passes."""
        with self._cond:
            if self._generation != seen or self._stop.is_set():
                return
            if self._source is None or self._listening:
                self._cond.wait(timeout)
                return
            self._listening = True
            self._listener = threading.get_ident()
        try:
            self._source.wait(timeout)
        finally:
            with self._cond:
                self._listening = False
                self._listener = None
                self._generation += 1
                self._cond.notify_all()

    def add_timer(self, first_due: float, fire: Callable[[], float | None]) -> None:
        """``fire`` runs at ``first_due``; it returns its next due time, or None to stop."""
        with self._cond:
            heapq.heappush(self._timers, (first_due, next(self._counter), fire))
        self.wake()

    def spin_once(self, timeout: float | None) -> bool:
        """Run at most one callback; return False when nothing ran before ``timeout``."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            with self._cond:
                if self._stop.is_set():
                    return False
                seen = self._generation
                now = time.monotonic()
                fire: Callable[[], float | None] | None = None
                entity: Dispatchable | None = None
                if self._timers and self._timers[0][0] <= now:
                    _, _, fire = heapq.heappop(self._timers)
                elif self._ready:
                    entity = self._ready.popleft()
                    self._queued.discard(id(entity))
                else:
                    wait = None if not self._timers else self._timers[0][0] - now
                    if deadline is not None:
                        left = deadline - now
                        if left <= 0:
                            return False
                        wait = left if wait is None else min(wait, left)
            if fire is not None:
                next_due = fire()
                if next_due is not None:
                    with self._cond:
                        heapq.heappush(self._timers, (next_due, next(self._counter), fire))
                return True
            if entity is not None:
                if entity.dispatch():
                    self.notify(entity)
                return True
            self.wait(seen, wait)
