"""What handing a message from one Python thread to another costs, apart from any framework.

rospy runs subscription callbacks in threads of their own, so a pinger written the rospy way keeps
its loop in the main thread and waits (``threading.Event``) for the reply its callback receives: each
round trip passes the reply from one thread to the other, and wakes a thread that slept in the kernel.
This measures that on the ping's core in the same run as the ping-pong, with no transport at all: a
waker thread polling awake (as hetros's callback thread does, yielding the CPU at every poll) hands a
token to the main thread, which sleeps in ``Event.wait`` (rospy's structure), under the policy
hetros's rospy gives it on a single core (``yield_to_callbacks``). A loop that runs the callbacks
itself (rclpy's ``spin_once``, hetros's own API) passes nothing between threads: the same token
moved within one thread is the baseline, and the difference of the two p50s is the floor the rospy
structure adds to a round trip, whatever carries the messages. Beside them: the hand-over under the
default policy (several times dearer on one core), and two threads that both poll (the thread
switches without the sleep).

Run as ``python -m hetros_bench._handover CPU``: prints one JSON line.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
import threading
import time
from typing import Any

from hetros.runtime import yield_to_callbacks

ROUNDS = 20_000


def _p50_us(sleeping: bool, as_the_shim_runs: bool = True) -> float:
    """The hand-over's p50; ``as_the_shim_runs``: the main thread under the policy hetros's rospy gives a
    node's main thread once its callback thread runs (``yield_to_callbacks``), else the default one."""
    asked, answered = [False], [False]
    woken = threading.Event()
    done = threading.Event()

    def waker() -> None:
        while not done.is_set():
            if not asked[0]:
                os.sched_yield()
                continue
            asked[0] = False
            if sleeping:
                woken.set()
            else:
                answered[0] = True

    thread = threading.Thread(target=waker, daemon=True)
    thread.start()
    if as_the_shim_runs:
        yield_to_callbacks()
    times = []
    for _ in range(ROUNDS):
        started = time.perf_counter_ns()
        asked[0] = True
        if sleeping:
            woken.wait(1.0)
            woken.clear()
        else:
            while not answered[0]:
                os.sched_yield()
            answered[0] = False
        times.append(time.perf_counter_ns() - started)
    done.set()
    thread.join()
    with contextlib.suppress(OSError):  # the next run's waker starts with the default policy, as the shim's does
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    return _p50(times)


def _one_thread_p50_us() -> float:
    """The same token's round within one thread: what a loop that runs its callbacks itself pays."""
    asked, answered = [False], [False]
    times = []
    for _ in range(ROUNDS):
        started = time.perf_counter_ns()
        asked[0] = True
        if asked[0]:
            asked[0] = False
            answered[0] = True
        while not answered[0]:
            pass
        answered[0] = False
        times.append(time.perf_counter_ns() - started)
    return _p50(times)


def _p50(times_ns: list[int]) -> float:
    """The median of ``times_ns``, in µs."""
    times_ns.sort()
    return times_ns[len(times_ns) // 2] / 1000.0


def measure(cpu: int | None) -> dict[str, Any]:
    if cpu is not None:
        os.sched_setaffinity(0, [cpu])
    _p50_us(True)  # warm-up: the first thousands of rounds run while the CPU's frequency settles
    sleeping, one_thread = _p50_us(True), _one_thread_p50_us()
    return {"event_wait_us": sleeping, "one_thread_us": one_thread, "floor_us": max(0.0, sleeping - one_thread),
            "event_wait_default_policy_us": _p50_us(True, as_the_shim_runs=False), "polling_us": _p50_us(False)}


if __name__ == "__main__":
    print(json.dumps(measure(int(sys.argv[1]) if len(sys.argv) > 1 and sys.argv[1] != "-" else None)))
