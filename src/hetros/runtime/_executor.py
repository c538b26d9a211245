"""The per-node callback queue (ROS-lite): a node's callbacks never run concurrently.

Event-driven: transports call :meth:`Executor.notify` when an entity may have
work, timers sit in a heap, and :meth:`Executor.spin` sleeps on one condition
until the earliest of the two. An idle node uses no CPU.
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


class Executor:
    def __init__(self, stop: threading.Event) -> None:
        self._stop = stop
        self._cond = threading.Condition()
        self._ready: deque[Dispatchable] = deque()
        self._queued: set[int] = set()
        self._timers: list[tuple[float, int, Callable[[], float | None]]] = []
        self._counter = itertools.count()
        self.entities = 0

    def notify(self, entity: Dispatchable) -> None:
        """Mark ``entity`` as having work (callable from any thread)."""
        with self._cond:
            key = id(entity)
            if key not in self._queued:
                self._queued.add(key)
                self._ready.append(entity)
                self._cond.notify()

    def wake(self) -> None:
        with self._cond:
            self._cond.notify_all()

    def add_timer(self, first_due: float, fire: Callable[[], float | None]) -> None:
        """``fire`` runs at ``first_due``; it returns its next due time, or None to stop."""
        with self._cond:
            heapq.heappush(self._timers, (first_due, next(self._counter), fire))
            self._cond.notify()

    def spin_once(self, timeout: float | None) -> bool:
        """Run at most one callback; return False when nothing ran before ``timeout``."""
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._cond:
            while True:
                if self._stop.is_set():
                    return False
                now = time.monotonic()
                if self._timers and self._timers[0][0] <= now:
                    _, _, fire = heapq.heappop(self._timers)
                    entity: Dispatchable | None = None
                    break
                if self._ready:
                    entity = self._ready.popleft()
                    self._queued.discard(id(entity))
                    fire = None  # type: ignore[assignment]
                    break
                wait = None if not self._timers else self._timers[0][0] - now
                if deadline is not None:
                    left = deadline - now
                    if left <= 0:
                        return False
                    wait = left if wait is None else min(wait, left)
                self._cond.wait(wait)
        if entity is None:
            next_due = fire()
            if next_due is not None:
                with self._cond:
                    heapq.heappush(self._timers, (next_due, next(self._counter), fire))
            return True
        if entity.dispatch():
            self.notify(entity)
        return True
