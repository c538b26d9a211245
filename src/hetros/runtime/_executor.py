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
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Protocol

from ..transport import WaitSource

# A hot spin hands the GIL over (os.sched_yield: 0.5 µs here, half of a poll) only every
# SPARSE_YIELD polls while no other thread of the process has woken the node: a poll then
# takes 0.4 µs instead of 1.0 and a message from another process is seen that much sooner
# (measured: round trip over raw iceoryx2's 1.8x -> 1.6x at 4 B-12 kB). Once a thread of this
# process has woken the node (an in-process publisher needs the GIL to publish), the spin
# yields at every poll: yielding every 4th cost an in-process hop 1.3 µs. Any other thread
# waits at most SPARSE_YIELD polls (a few µs) for the GIL.
SPARSE_YIELD = 8

# A hot spin polls its subscriptions directly; the wake channel (work for anything else the node has: a
# service, a subscription that is not polled) and the stop flag only every SOURCE_EVERY polls. Asking them
# at every poll cost a third of it (0.25 µs of 0.75), and so the time a polled message waits to be seen.
SOURCE_EVERY = 4


# a stream hotter than HOT (its typical gap) spins for twice its gap, at least LOW and at most HIGH seconds
HOT = 500e-6
LOW = 50e-6
HIGH = 1e-3


class AdaptiveSpin:
    """How long to wait awake before blocking: on a hot stream, about two message gaps.

    A blocking wake-up of another CPU costs tens of microseconds here; it is worth
    avoiding only when messages come about that often (a request/reply exchange, a
    multi-kHz stream). A stream whose typical gap is longer than ``HOT`` never spins,
    nor does one that went quiet: a 100 Hz or 1 kHz subscriber sleeps between messages.
    """

    def __init__(self) -> None:
        self.last = 0.0
        self.gap = 0.0

    def budget(self, now: float) -> float:
        """How long to poll from ``now`` (``time.perf_counter``, which the caller reads anyway)."""
        gap = self.gap
        if gap > HOT or now - self.last > HOT:
            return 0.0
        return min(max(2.0 * gap, LOW), HIGH)

    def arrived(self, now: float) -> None:
        """Track the typical gap (``now`` from ``time.perf_counter``, which the caller has read
        anyway): it falls at once to a shorter gap and rises slowly on a longer one."""
        gap = now - self.last
        self.gap = gap if self.gap == 0.0 or gap < self.gap else 0.8 * self.gap + 0.2 * gap
        self.last = now


class Dispatchable(Protocol):
    def dispatch(self) -> bool:
        """Run one callback if there is work; return whether one ran."""
        ...

    def pending(self) -> bool:
        """Whether more work may be waiting (False only when surely not)."""
        ...


class Executor:
    def __init__(self, stop: threading.Event, source: WaitSource | None = None) -> None:
        self._stop = stop
        self._source = source
        # entered directly (a C call); the condition's own __enter__ is a Python method on the hot path
        self._lock = threading.RLock()
        self._cond = threading.Condition(self._lock)
        self._sleepers = 0  # threads in _cond.wait: only they need a notify_all (~0.2 µs even for none)
        self._generation = 0
        self._listening = False
        self._listener: int | None = None
        self._ready: deque[Dispatchable] = deque()
        self._queued: set[int] = set()
        self._timers: list[tuple[float, int, Callable[[], float | None]]] = []
        self._counter = itertools.count()
        self._spin = AdaptiveSpin()
        self._polled: list[Dispatchable] = []
        self._next_polled = 0
        self._spinner = 0  # the thread in a hot spin (its ident), 0 when none
        # polls between GIL hand-overs in a hot spin: sparse while only other processes feed the
        # node, every poll from the first wake-up by another thread of this process on
        self.yield_every = SPARSE_YIELD
        self.entities = 0
        self.arrivals = 0  # see arrived()

    @property
    def generation(self) -> int:
        """Changes whenever something may have become ready; pass it to :meth:`wait`."""
        return self._generation

    def notify(self, entity: Dispatchable) -> None:
        """Mark ``entity`` as having work (callable from any thread)."""
        with self._lock:
            key = id(entity)
            if key not in self._queued:
                self._queued.add(key)
                self._ready.append(entity)
            interrupt = self._woken()
        if interrupt and self._source is not None:
            self._source.interrupt()

    def arrived(self) -> None:
        """Something was delivered outside the callback queue (a reply, a message for a take loop or an
        action's answer): every waiter rechecks, and ``arrivals`` counts it, so that a loop waiting for
        work (rclpy's ``spin_once``) can tell it from a wait that merely ended."""
        self.arrivals += 1
        self.wake()

    def wake(self) -> None:
        """Something may be ready: every waiter rechecks (callable from any thread)."""
        with self._lock:
            interrupt = self._woken()
        if interrupt and self._source is not None:
            self._source.interrupt()

    def _woken(self) -> bool:
        """Under the condition: a new generation for every waiter; whether the source must be interrupted."""
        self._generation += 1
        if self._sleepers:
            self._cond.notify_all()
        if self._spinner and self._spinner != threading.get_ident():
            self.yield_every = 1
        return self._listening and self._listener != threading.get_ident()

    def wait(self, seen: int, timeout: float | None) -> None:
        """Block until the generation differs from ``seen`` or ``timeout`` passes."""
        with self._lock:
            if self._generation != seen or self._stop.is_set():
                return
            if self._source is None or self._listening:
                self._sleepers += 1
                try:
                    self._cond.wait(timeout)
                finally:
                    self._sleepers -= 1
                return
            self._listening = True
            self._listener = threading.get_ident()
        try:
            self._source.wait(timeout)
        finally:
            with self._lock:
                self._listening = False
                self._listener = None
                self._woken()

    def alone(self) -> None:
        """No other thread of this process needs the GIL often from now (a rospy main thread that went into
        ``spin()``): a hot spin hands it over every SPARSE_YIELD polls again, until a thread of this
        process wakes the node (see _woken)."""
        self.yield_every = SPARSE_YIELD

    def poll_while_spinning(self, entity: Dispatchable) -> None:
        """Let a hot spin dispatch ``entity`` (a subscription callback) as soon as it has a
        message, instead of through its wake function and the ready queue: that round
        cost a callback 3.7 µs per message, as much as taking the message itself."""
        self._polled = [*self._polled, entity]

    def drain(self, seconds: float) -> int:
        """Once the graph stops: run the callbacks of messages already delivered to this node's subscriptions,
        until none is left or ``seconds`` pass; how many ran. The launch stops the processes with shutdown
        hooks first so that what a hook publishes finds its subscribers running; a subscriber told to stop
        a moment later still has it to handle (rospy's on_shutdown example, heard by its listener)."""
        end = time.monotonic() + seconds
        ran, progress = 0, True
        while progress and time.monotonic() < end:
            progress = False
            for entity in self._polled:
                if entity.dispatch():
                    ran, progress = ran + 1, True
        return ran

    def stop_polling(self, entity: Dispatchable) -> None:
        self._polled = [polled for polled in self._polled if polled is not entity]

    def add_timer(self, first_due: float, fire: Callable[[], float | None]) -> None:
        """``fire`` runs at ``first_due``; it returns its next due time, or None to stop."""
        with self._lock:
            heapq.heappush(self._timers, (first_due, next(self._counter), fire))
        self.wake()

    def spin_once(self, timeout: float | None) -> bool:
        """Run at most one callback; return False when nothing ran before ``timeout``, or as soon as
        something arrived outside the callback queue (a reply, an action's answer: see ``arrived``), so
        that a loop of ``spin_once`` and ``future.done()`` sees it at once."""
        now = time.monotonic()
        deadline = None if timeout is None else now + timeout
        arrivals = self.arrivals
        hot = self._hot_path(now, timeout) if self._polled else _WORK
        if hot is _DISPATCHED:
            return True
        while True:
            with self._lock:
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
                    with self._lock:
                        heapq.heappush(self._timers, (next_due, next(self._counter), fire))
                return True
            if entity is not None:
                if entity.dispatch():
                    self._spin.arrived(time.perf_counter())
                    # asked instead of dispatching again to find the FIFO empty; later arrivals wake it
                    if entity.pending():
                        self.notify(entity)
                    return True
                continue  # a late wake of a polled subscription whose message a hot spin already took
            # a hot path that found nothing has spun already: wait at once
            spun = _NOTHING if hot is _NOTHING else self._spin_for_work(seen, wait)
            hot = _WORK
            if spun is _DISPATCHED:
                return True
            if spun is _NOTHING:
                self.wait(seen, wait)
            if self.arrivals != arrivals:
                return False

    def _hot_path(self, now: float, timeout: float | None) -> object:
        """Poll straight away when nothing is queued and no timer is due: a ping-pong's reply comes within
        microseconds of the call, and the queue's checks under the lock, before the poll starts, added
        2 µs to its round trip. Without the lock: the generation is read first, so what becomes ready
        meanwhile ends the poll (``_WORK``), and the queue then runs it."""
        seen = self._generation
        timers = self._timers
        try:
            due = timers[0][0] - now if timers else None
        except IndexError:  # another thread took the last timer between the two reads
            return _WORK
        if self._ready or (due is not None and due <= 0) or self._stop.is_set():
            return _WORK
        wait = timeout if due is None else due if timeout is None else min(due, timeout)
        return self._spin_for_work(seen, wait)

    def _spin_for_work(self, seen: int, wait: float | None) -> object:
        """On a hot stream, poll awake for a while instead of blocking: ``_DISPATCHED`` when it
        ran a polled callback, ``_WORK`` when other work came, else ``_NOTHING``.

        Polling a reader costs ~0.2 µs, a blocking wake-up of another CPU tens of
        microseconds: it pays only when messages come about that often (see AdaptiveSpin).
        """
        now = time.perf_counter()
        budget = self._spin.budget(now)
        if not budget:
            return _NOTHING
        end = now + (budget if wait is None else min(budget, wait))
        source = self._source
        dispatch_polled = self._dispatch_polled
        polls = turns = 0
        self._spinner = threading.get_ident()
        try:
            while time.perf_counter() < end:
                if dispatch_polled():
                    return _DISPATCHED
                turns += 1
                if turns == SOURCE_EVERY:
                    turns = 0
                    if source is not None:
                        source.poll()
                    if self._stop.is_set():
                        return _WORK
                if self._generation != seen:
                    # the source also wakes a polled subscription whose message came after its turn above:
                    # taken here, it skips the ready queue's longer way (half the messages of a ping-pong)
                    return _DISPATCHED if dispatch_polled() else _WORK
                polls += 1
                if polls >= self.yield_every:
                    polls = 0
                    os.sched_yield()  # see SPARSE_YIELD
            return _NOTHING
        finally:
            self._spinner = 0

    def _dispatch_polled(self) -> bool:
        """One turn over the polled subscriptions, round robin so that a busy one cannot starve the others:
        whether one ran its callback."""
        polled = self._polled
        count = len(polled)
        for turn in range(count):
            index = (self._next_polled + turn) % count
            if polled[index].dispatch():
                self._next_polled = index + 1
                self._spin.arrived(time.perf_counter())
                return True
        return False

    def hot_spin(self, spinning: bool) -> None:
        """A thread starts (True) or ends a hot spin of its own (``Subscription.take``): wake-ups
        from other threads meanwhile tell that this process feeds the node (``yield_every``)."""
        self._spinner = threading.get_ident() if spinning else 0


def yield_to_callbacks() -> None:
    """On a single core, the calling thread (a node's main thread, once its callback thread runs) does not
    preempt the thread that wakes it: SCHED_BATCH.

    A rospy node's main thread often waits (``threading.Event``, a condition) for what its callback thread
    receives. On one core the woken main thread preempted the callback thread while that still held the GIL
    and the lock it had just set, and waited for both: 17 µs per hand-over against 8 here
    (``benchmarks/hetros_bench/_handover.py``). Threads of one interpreter cannot run Python at
    the same time anyway, so among themselves the preemption gained nothing. The callback thread keeps the
    normal policy: a message that wakes it still preempts the main thread. With more than one core the main
    thread wakes on another, and nothing changes; where the policy cannot be set (a sandbox), nothing does.
    """
    try:
        if len(os.sched_getaffinity(0)) == 1 and os.sched_getscheduler(0) == os.SCHED_OTHER:
            os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))
    except (AttributeError, OSError):
        pass


# what Executor._spin_for_work found
_DISPATCHED, _WORK, _NOTHING = object(), object(), object()
