"""The executor's hot spin: polled callbacks run straight from the spin, in turn, and only while it is hot."""

from __future__ import annotations

import os
import threading
import time

import pytest

from hetros.runtime import _executor as executor_module
from hetros.runtime._executor import SPARSE_YIELD, Executor


class _Queue:
    """A dispatchable with ``count`` messages waiting: each dispatch runs one and records its name."""

    def __init__(self, name: str, count: int, ran: list[str]) -> None:
        self.name = name
        self.count = count
        self.ran = ran

    def dispatch(self) -> bool:
        if not self.count:
            return False
        self.count -= 1
        self.ran.append(self.name)
        return True

    def pending(self) -> bool:
        return self.count > 0


def _hot(executor: Executor) -> None:
    """As after a burst of messages: the spin has a budget (HIGH, whenever the spin starts: a busy machine
    may start it more than HOT after the burst, when the adaptive rule would give none; that rule has a
    test of its own)."""
    now = time.perf_counter()
    executor._spin.arrived(now - 10e-6)
    executor._spin.arrived(now)
    executor._spin.budget = lambda now: executor_module.HIGH  # type: ignore[method-assign]


def test_a_hot_spin_runs_polled_callbacks_in_turn() -> None:
    executor = Executor(threading.Event())
    ran: list[str] = []
    for name in "abc":
        executor.poll_while_spinning(_Queue(name, 100, ran))
    _hot(executor)
    for _ in range(9):
        assert executor.spin_once(1.0)
    assert ran == list("abcabcabc"), "a busy subscription must not starve the others"


def test_a_stopped_executor_drains_what_was_delivered_within_its_bound() -> None:
    """Stopped, spin_once runs nothing; drain runs every delivered message, in turn, and no more."""
    stop = threading.Event()
    executor = Executor(stop)
    ran: list[str] = []
    executor.poll_while_spinning(_Queue("a", 2, ran))
    executor.poll_while_spinning(_Queue("b", 1, ran))
    stop.set()
    assert not executor.spin_once(0.0)
    assert executor.drain(5.0) == 3
    assert ran == ["a", "b", "a"]
    endless = Executor(stop)
    endless.poll_while_spinning(_Queue("c", 10**9, ran))
    started = time.monotonic()
    assert endless.drain(0.05) > 0
    assert time.monotonic() - started < 5.0, "a drain ends at its bound even if messages keep coming"


def test_a_polled_callback_that_stops_being_polled_is_left_alone() -> None:
    executor = Executor(threading.Event())
    ran: list[str] = []
    busy, other = _Queue("busy", 100, ran), _Queue("other", 100, ran)
    executor.poll_while_spinning(busy)
    executor.poll_while_spinning(other)
    executor.stop_polling(busy)
    _hot(executor)
    assert executor.spin_once(1.0)
    assert ran == ["other"]


def test_an_idle_spin_gives_up_and_times_out() -> None:
    executor = Executor(threading.Event())
    ran: list[str] = []
    executor.poll_while_spinning(_Queue("empty", 0, ran))
    _hot(executor)
    start = time.monotonic()
    assert not executor.spin_once(0.05)
    assert ran == [] and time.monotonic() - start < 1.0


def test_a_cold_executor_does_not_poll() -> None:
    """Without a hot stream the spin has no budget: work arrives through notify, not polling."""
    executor = Executor(threading.Event())
    ran: list[str] = []
    queue = _Queue("q", 5, ran)
    executor.poll_while_spinning(queue)
    assert not executor.spin_once(0.02)
    assert ran == []
    executor.notify(queue)
    assert executor.spin_once(0.02)
    assert ran == ["q"]


class _Empty:
    """A polled subscription with nothing to take: counts the polls of a hot spin."""

    def __init__(self) -> None:
        self.polls = 0

    def dispatch(self) -> bool:
        self.polls += 1
        return False

    def pending(self) -> bool:
        return False


def test_a_hot_spin_hands_the_gil_over_at_every_poll_only_once_a_thread_of_this_process_woke_the_node(
        monkeypatch: pytest.MonkeyPatch) -> None:
    executor = Executor(threading.Event())
    empty = _Empty()
    executor.poll_while_spinning(empty)
    yields: list[int] = []
    monkeypatch.setattr(executor_module.os, "sched_yield", lambda: yields.append(1))

    def spin() -> None:
        empty.polls, yields[:] = 0, []
        executor._spin.gap, executor._spin.last = 400e-6, time.perf_counter()  # a budget of 0.8 ms
        executor.spin_once(0.01)

    spin()
    assert empty.polls >= 2 * SPARSE_YIELD and len(yields) == empty.polls // SPARSE_YIELD, \
        "fed from other processes only: the GIL is handed over every few polls"
    executor.wake()  # from the spinning thread itself (a shared-memory wake-up): no change
    executor.hot_spin(True)
    executor.wake()
    assert executor.yield_every == SPARSE_YIELD
    waker = threading.Thread(target=executor.wake)  # an in-process publisher, while a thread spins
    waker.start()
    waker.join()
    executor.hot_spin(False)
    assert executor.yield_every == 1
    spin()
    assert empty.polls >= 2 and len(yields) == empty.polls, "an in-process publisher gets the GIL at every poll"


class _LateSource:
    """A wake channel whose poll finds the message that arrived just after the polled subscription's turn:
    it puts the message in ``queue`` and wakes the subscription, as the shared-memory channel does."""

    def __init__(self, executor: Executor, queue: _Queue, polls_before: int) -> None:
        self.executor, self.queue, self.polls_before = executor, queue, polls_before

    def poll(self) -> None:
        self.polls_before -= 1
        if self.polls_before == 0:
            self.queue.count += 1
            self.executor.notify(self.queue)

    def wait(self, timeout: float | None) -> None:
        time.sleep(timeout or 0.0)

    def interrupt(self) -> None:
        pass


def test_a_message_the_wake_channel_finds_is_run_from_the_spin_and_its_late_wake_runs_nothing() -> None:
    """The channel's poll wakes a polled subscription whose message came after its turn: the spin runs it at
    once, and the wake, still queued, neither runs a callback again nor ends the next spin_once early."""
    ran: list[str] = []
    queue = _Queue("q", 0, ran)
    executor = Executor(threading.Event())
    source = _LateSource(executor, queue, polls_before=1)
    executor._source = source
    executor.poll_while_spinning(queue)
    _hot(executor)
    dispatched: list[bool] = []
    spin_for_work = executor._spin_for_work
    executor._spin_for_work = lambda seen, wait: dispatched.append(  # type: ignore[method-assign]
        (found := spin_for_work(seen, wait)) is executor_module._DISPATCHED) or found
    assert executor.spin_once(1.0)
    assert ran == ["q"] and dispatched == [True], "run from the spin, not by the ready queue's way"
    _hot(executor)
    started = time.monotonic()
    assert not executor.spin_once(0.05), "the late wake found nothing to run: no work done"
    assert ran == ["q"] and time.monotonic() - started >= 0.05


def test_the_hot_path_leaves_a_due_timer_and_queued_work_their_turn_first() -> None:
    ran: list[str] = []
    executor = Executor(threading.Event())
    executor.poll_while_spinning(_Queue("polled", 10, ran))
    executor.add_timer(time.monotonic() - 1.0, lambda: ran.append("timer") or None)
    queued = _Queue("queued", 1, ran)
    executor.notify(queued)
    _hot(executor)
    for _ in range(3):
        assert executor.spin_once(1.0)
    assert ran == ["timer", "queued", "polled"]


def test_a_thread_on_one_core_stops_preempting_its_waker_and_one_on_several_cores_is_left_alone() -> None:
    """yield_to_callbacks: what hetros's rospy does to a node's main thread once its callback thread runs."""
    from hetros.runtime import yield_to_callbacks

    cores = sorted(os.sched_getaffinity(0))
    seen: dict[str, int] = {}

    def on(name: str, cpus: list[int]) -> None:
        os.sched_setaffinity(0, cpus)  # this thread only
        yield_to_callbacks()
        seen[name] = os.sched_getscheduler(0)

    for name, cpus in (("one", cores[:1]), ("all", cores)):
        thread = threading.Thread(target=on, args=(name, cpus))
        thread.start()
        thread.join()
    assert seen["one"] == os.SCHED_BATCH
    if len(cores) > 1:
        assert seen["all"] == os.SCHED_OTHER
    assert os.sched_getscheduler(0) == os.SCHED_OTHER, "other threads keep their policy"
