"""Run a project for a while and watch it from outside: what the advisor's profile and its
``--verify`` are made of.

The project runs as ``hetros launch`` in a child process, exactly as a user starts it. From
beside it this module taps every topic for times, sizes and header stamps (meta taps: no
copy of the data) and reads each process' figures (node times, CPU) over its control socket,
once when the warm-up ends and again just before the launch ends, so that start-up
(imports, first allocations, a simulator's compile) is left out of both.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._errors import AdviseError, Error
from ..plan import Plan
from ..runtime import PROFILE_VARIABLE
from ._chains import Published

if TYPE_CHECKING:
    from ..launch import RunningLaunch

POLL_S = 0.5


@dataclass
class Observation:
    """What one watched run gave: per process the figures at the warm-up's end and at the end,
    per topic its publishes after the warm-up, and the window they span."""

    plan: Plan
    window_s: float
    early: dict[str, dict[str, Any]] = field(default_factory=dict)
    late: dict[str, dict[str, Any]] = field(default_factory=dict)
    published: dict[str, list[Published]] = field(default_factory=dict)
    # one encoded message per topic asked for (``samples``): the first published after the warm-up
    samples: dict[str, bytes] = field(default_factory=dict)


def observe(project: Path, plan: Plan, *, duration: float, warmup: float, profiling: bool,
            log: Path, start_timeout: float = 120.0, samples: frozenset[str] = frozenset()) -> Observation:
    """Launch ``project`` for ``duration`` s (``warmup`` s of it not counted) and watch it; keep one
    message of each topic in ``samples`` (encoded). A co-simulation in it runs at the lowest priority, so
    that the software beside it is measured as it would run beside real hardware."""
    from ..launch import SIMULATOR_NICE_VARIABLE

    if not 0 <= warmup < duration:
        raise AdviseError(f"the warm-up must be shorter than the run: {warmup:g} s of {duration:g} s")
    env = dict(os.environ)
    env[PROFILE_VARIABLE] = "1" if profiling else "0"
    env[SIMULATOR_NICE_VARIABLE] = "19"
    log.parent.mkdir(parents=True, exist_ok=True)
    command = [sys.executable, "-m", "hetros", "launch", str(project), "--duration", f"{duration:g}",
               "--start-timeout", f"{start_timeout:g}"]
    with log.open("w", encoding="utf-8") as output:
        child = subprocess.Popen(command, env=env, stdout=output, stderr=subprocess.STDOUT)
        try:
            seen = _watch(child, plan, duration=duration, warmup=warmup, start_timeout=start_timeout,
                          samples=samples)
        finally:
            if child.poll() is None:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    child.wait(timeout=duration + start_timeout + 60)
            if child.poll() is None:
                child.terminate()
                child.wait(timeout=30)
    if child.returncode:
        tail = "\n".join(log.read_text(encoding="utf-8", errors="replace").splitlines()[-15:])
        raise AdviseError(f"the launch of {project} failed (exit {child.returncode}); its output ({log}) ends:\n"
                          f"{tail}")
    return seen


def _find(child: subprocess.Popen[bytes], deadline: float) -> RunningLaunch:
    from ..launch import RunningLaunch, running

    prefix = f"{child.pid}x"
    while time.monotonic() < deadline and child.poll() is None:
        mine = [r for r in running() if r.session.startswith(prefix)]
        if mine:
            with contextlib.suppress(Error):
                return RunningLaunch(mine[0])
        time.sleep(0.1)
    raise AdviseError("the launch did not register within the start timeout (or ended at once); see its log")


def _stats(launch: RunningLaunch) -> dict[str, dict[str, Any]] | None:
    """Each process' figures, or None while one of them does not answer yet."""
    found: dict[str, dict[str, Any]] = {}
    for process in launch.processes():
        try:
            answer, _ = launch.ask(process, {"op": "stats"}, timeout=5.0)
        except Error:
            return None
        found[process] = answer
    return found


def _watch(child: subprocess.Popen[bytes], plan: Plan, *, duration: float, warmup: float,
           start_timeout: float, samples: frozenset[str]) -> Observation:
    launch = _find(child, time.monotonic() + start_timeout)
    topics = sorted(n for n, c in plan.channels.items()
                    if c.kind == "topic" and c.publishers and launch.plan.tap_sites(n)[1])
    published: dict[str, list[Published]] = {topic: [] for topic in topics}
    counting_from = [0]  # wall ns from which publishes count (set when the warm-up ends)
    stop = threading.Event()
    kept: dict[str, bytes] = {}
    threads = [threading.Thread(target=_tap, args=(launch, topic, published[topic], counting_from, stop,
                                                   kept if topic in samples else None),
                                daemon=True, name=f"advise-tap:{topic}") for topic in topics]
    for thread in threads:
        thread.start()
    while (started := _stats(launch)) is None:
        if child.poll() is not None:
            raise AdviseError("the launch ended before all of its processes answered")
        time.sleep(POLL_S)
    begin = time.monotonic()
    time.sleep(max(0.0, warmup - (time.monotonic() - begin)))
    early = _stats(launch) or started
    counting_from[0] = time.time_ns()
    window_start = time.monotonic()
    late, late_at = early, window_start
    end = begin + duration - 1.0  # the last figures a little before the launch stops its nodes
    while time.monotonic() < end and child.poll() is None:
        time.sleep(POLL_S)
        now = _stats(launch)
        if now is not None:
            late, late_at = now, time.monotonic()
    stop.set()
    window = late_at - window_start
    if window <= 0:
        raise AdviseError(f"no figures after the warm-up ({warmup:g} s): run longer (--duration)")
    ended = time.time_ns() - int((time.monotonic() - late_at) * 1e9)
    for events in published.values():
        events[:] = [p for p in events if p.time_ns <= ended]
    return Observation(plan, window, early, late, published, kept)


def _tap(launch: RunningLaunch, topic: str, into: list[Published], counting_from: list[int],
         stop: threading.Event, keep: dict[str, bytes] | None) -> None:
    """Collect ``topic``'s publishes (after the warm-up) until ``stop``, and into ``keep`` the first
    one's bytes; attach again while the topic's publisher is not running yet."""
    while not stop.is_set():
        try:
            for event in launch.tap(topic, data=keep is not None):
                if stop.is_set():
                    return
                if event is not None and counting_from[0] and event.time_ns >= counting_from[0]:
                    into.append(Published(event.time_ns, event.size, event.stamp))
                    if keep is not None and event.data is not None:
                        keep.setdefault(topic, event.data)
            return
        except Error:
            time.sleep(0.2)
