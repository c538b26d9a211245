"""What handing a message from one Python thread to another costs, apart from any framework.

rospy runs subscription callbacks in threads of their own, so a pinger written the rospy way keeps
its loop in the main thread and waits (``threading.Event``) for the reply its callback receives: each
round trip wakes a thread that slept in the kernel. This measures that wake on the ping's core in the
same run as the ping-pong, with no transport at all: a waker thread polling awake (as hetros's
callback thread does, yielding the CPU at every poll) hands a token to the main thread, which either
sleeps in ``Event.wait`` (rospy's structure) or polls awake too (the structure of a loop that runs the
callbacks itself, as rclpy's ``spin_once`` and hetros's own API do). The difference of the two p50s is
the floor the rospy structure adds to a round trip, whatever carries the messages. The sleeping main
thread runs under the policy hetros's rospy gives it on a single core (``yield_to_callbacks``); the
default policy's hand-over, several times dearer there, is reported beside it.

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
    times.sort()
    return times[len(times) // 2] / 1000.0


def measure(cpu: int | None) -> dict[str, Any]:
    if cpu is not None:
        os.sched_setaffinity(0, [cpu])
    _p50_us(True)  # warm-up: the first thousands of rounds run while the CPU's frequency settles
    sleeping, polling = _p50_us(True), _p50_us(False)
    return {"event_wait_us": sleeping, "event_wait_default_policy_us": _p50_us(True, as_the_shim_runs=False),
            "polling_us": polling, "floor_us": max(0.0, sleeping - polling)}


if __name__ == "__main__":
    print(json.dumps(measure(int(sys.argv[1]) if len(sys.argv) > 1 and sys.argv[1] != "-" else None)))
