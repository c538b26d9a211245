"""The hops a mapping can give an edge, measured on this machine with hetros itself: what the advisor's
calibration is made of, so that ``hetros advise`` needs nothing beyond the library.

Three rows, each a ping-pong of ``sensor_msgs/Image`` messages whose header carries the send time; the
echo side records the one-way latency of each message it takes:

- ``inproc``: both ends threads of one process on one graph, pinned to one CPU (as a process target with
  ``cpus: [n]`` is); the arrays travel read-only, with no copy;
- ``shm``: the ends in two processes on two CPUs, the echo a subscription callback (as users write it),
  the ping a ``take`` loop; the arrays cross shared memory, the echo's reply copies them once;
- ``copy``: one ``numpy.copyto`` of the payload (what a gateway pays per message into hardware).

The benchmark (``benchmarks/latency.py``) measures the same rows beside other systems' for its tables; this
is the calibration's own, short, run: each end in a fresh interpreter (``python -m hetros.advise._measure``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import AdviseError, TakeTimeoutError

SIZES = (4, 3072, 196608, 3145728)
# a ping's sequence numbers before it stops the echo: the first is a probe, then warm-up and measured
PROBE, STOP = -1, -2


def repetitions(size: int) -> tuple[int, int]:
    """(warm-up, measured) messages at ``size`` bytes: fewer of the large ones, which take milliseconds."""
    return (10, 100) if size <= 196608 else (5, 20)


def hop_table(sizes: tuple[int, ...] = SIZES) -> dict[str, list[tuple[int, float, float]]]:
    """Per row (``inproc``, ``shm``, ``copy``): (size, one-way p50 µs, p99 µs) at each of ``sizes``."""
    cpus = sorted(os.sched_getaffinity(0))
    pinned = cpus[:2] if len(cpus) >= 2 else []
    table: dict[str, list[tuple[int, float, float]]] = {"inproc": [], "shm": [], "copy": []}
    with tempfile.TemporaryDirectory(prefix="hetros-measure-") as folder:
        for size in sizes:
            warmup, reps = repetitions(size)
            config = {"size": size, "warmup": warmup, "reps": reps, "cpus": pinned, "folder": folder}
            table["copy"].append(_row(size, copy_times(size, warmup, reps)))
            table["inproc"].append(_row(size, _run_ends(config, ["inproc"])))
            table["shm"].append(_row(size, _run_ends(config, ["echo", "ping"])))
    return table


# the share of the machine's CPUs other processes may keep busy before an advice is refused: a profile and a
# calibration measured beside another job carry its load (a 3 kB hop of 1,055 µs where 16 µs was measured later)
BUSY_LIMIT = 0.25
# how far the calibration's copy of CHECK_SIZE bytes may be from a copy measured now before it is measured again
CHECK_SIZE = 196608
CHECK_TOLERANCE = 1.5


def busy_share(seconds: float = 1.0) -> float:
    """The share of this machine's CPU time spent outside the idle task over ``seconds`` (``/proc/stat``): what
    other processes keep busy while this one waits; 0.0 where the kernel does not say."""
    def sample() -> tuple[int, int]:
        fields = [int(v) for v in Path("/proc/stat").read_text(encoding="ascii").split("\n", 1)[0].split()[1:]]
        idle = fields[3] + (fields[4] if len(fields) > 4 else 0)  # idle and iowait
        return sum(fields[:8]), idle
    try:
        total_before, idle_before = sample()
        time.sleep(seconds)
        total, idle = sample()
    except (OSError, ValueError, IndexError):
        return 0.0
    spent = total - total_before
    return 0.0 if spent <= 0 else max(0.0, min(1.0, 1.0 - (idle - idle_before) / spent))


def copy_check_us() -> float:
    """A copy of CHECK_SIZE bytes now (p50 µs of a short run): whether a cached calibration still holds."""
    return _row(CHECK_SIZE, copy_times(CHECK_SIZE, 10, 60))[1]


def _row(size: int, samples_ns: list[int]) -> tuple[int, float, float]:
    if not samples_ns:
        raise AdviseError(f"measuring {size}-byte hops gave no samples")
    values = np.asarray(samples_ns, dtype=np.float64) / 1000.0
    return size, float(np.percentile(values, 50)), float(np.percentile(values, 99))


def copy_times(size: int, warmup: int, reps: int) -> list[int]:
    """``reps`` timed ``numpy.copyto`` of ``size`` bytes (ns) after ``warmup`` untimed ones."""
    source = np.random.default_rng(0).integers(0, 255, size, dtype=np.uint8)
    target = np.empty_like(source)
    times = []
    for index in range(warmup + reps):
        start = time.monotonic_ns()
        np.copyto(target, source)
        if index >= warmup:
            times.append(time.monotonic_ns() - start)
    return times


def _run_ends(config: dict[str, Any], roles: list[str]) -> list[int]:
    """Start one interpreter per role (the echo first), wait for them; the echo's one-way samples (ns)."""
    from ..transport import new_session

    config = {**config, "session": new_session()}
    path = Path(config["folder"]) / f"{roles[0]}-{config['size']}.json"
    path.write_text(json.dumps(config), encoding="utf-8")
    ends = [subprocess.Popen([sys.executable, "-m", "hetros.advise._measure", role, str(path)],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True) for role in roles]
    failed = []
    for role, end in zip(roles, ends, strict=True):
        try:
            _, err = end.communicate(timeout=300)
        except subprocess.TimeoutExpired:
            for other in ends:
                other.kill()
            raise AdviseError(f"measuring {config['size']}-byte hops: the {role} end ran past 300 s") from None
        if end.returncode != 0:
            failed.append(f"{role} exited {end.returncode}: {err.strip()[-600:]}")
    if failed:
        raise AdviseError(f"measuring {config['size']}-byte hops failed: {'; '.join(failed)}")
    samples: list[int] = json.loads((path.with_suffix(".out")).read_text(encoding="utf-8"))
    return samples


# -- the ends (each in its own interpreter) ------------------------------------------------------------------

def ping_pong_plan(depth: int = 16) -> Any:
    """Two process targets, ``ping`` publishing /send and taking /recv, ``echo`` the other way, over shared
    memory: the plan of a ping-pong between processes (the calibration's, the latency benchmark's)."""
    from ..plan import ChannelPlan, EdgePlan, NodePlan, Plan, TargetPlan
    from ..transport import QoS

    image = "sensor_msgs/msg/Image"
    qos = QoS(depth=depth, publish_timeout=30.0)
    return Plan(
        "ping_pong", "/", (),
        {"p0": TargetPlan("p0", "process"), "p1": TargetPlan("p1", "process")},
        {"ping": NodePlan("ping", "m:f", "p0", publish={"/send": image}, subscribe={"/recv": image}),
         "echo": NodePlan("echo", "m:f", "p1", publish={"/recv": image}, subscribe={"/send": image})},
        {"/send": ChannelPlan("/send", image, "topic", qos, ("ping",), ("echo",)),
         "/recv": ChannelPlan("/recv", image, "topic", qos, ("echo",), ("ping",))},
        (EdgePlan("/send", "ping", "echo", "shm"), EdgePlan("/recv", "echo", "ping", "shm")),
    )


def _stamped(image: Any, data: Any, stamp: int, seq: int) -> Any:
    message = image(data=data)
    message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
    message.header.frame_id = str(seq)
    return message


def _stamp_of(message: Any) -> tuple[int, int]:
    return (message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec,
            int(message.header.frame_id))


def _ping(node: Any, config: dict[str, Any]) -> None:
    """Send, wait for the reply, send the next: a probe until the echo answers, then warm-up and measured."""
    from ..msg import registry

    image = registry().get("sensor_msgs/msg/Image")
    pub, sub = node.create_publisher(image, "/send"), node.create_subscription(image, "/recv")
    payload = np.zeros(config["size"], dtype=np.uint8)
    payload.flags.writeable = False
    deadline = time.monotonic() + 30
    while True:
        pub.publish(_stamped(image, payload, time.monotonic_ns(), PROBE))
        try:
            sub.take(timeout=0.2)
            break
        except TakeTimeoutError:  # until the echo subscribes
            if time.monotonic() > deadline:
                raise AdviseError("the echo end never answered") from None
    for seq in range(config["warmup"] + config["reps"]):
        pub.publish(_stamped(image, payload, time.monotonic_ns(), seq))
        while _stamp_of(sub.take(timeout=30))[1] != seq:
            pass
    pub.publish(_stamped(image, payload[:0], time.monotonic_ns(), STOP))


def _echo(node: Any, config: dict[str, Any], copy: bool, done: Callable[[list[int]], None]) -> None:
    """Answer every message from a callback, recording its one-way latency; stop the graph at the stop."""
    from ..msg import registry

    image = registry().get("sensor_msgs/msg/Image")
    pub = node.create_publisher(image, "/recv")
    one_way: list[int] = []

    def answer(message: Any) -> None:
        now = time.monotonic_ns()
        stamp, seq = _stamp_of(message)
        if seq == STOP:
            node.graph.shutdown()  # ends the spin below (in one process, after the ping has finished)
            return
        if seq >= config["warmup"]:
            one_way.append(now - stamp)
        pub.publish(_stamped(image, message.data.copy() if copy else message.data, stamp, seq))

    node.create_subscription(image, "/send", answer)
    node.spin()
    done(one_way)


def _end(role: str, path: Path) -> None:
    from ..runtime import Graph, Node

    config = json.loads(path.read_text(encoding="utf-8"))
    cpus = config["cpus"]
    write = path.with_suffix(".out").write_text

    def keep(samples: list[int]) -> None:
        write(json.dumps(samples), encoding="utf-8")

    if role == "inproc":
        if cpus:
            os.sched_setaffinity(0, cpus[:1])
        graph = Graph.standalone()
        echo = threading.Thread(target=_echo, args=(Node("echo", graph), config, False, keep), daemon=True)
        echo.start()
        _ping(Node("ping", graph), config)
        echo.join(60)
        graph.close()
        return
    if cpus:
        os.sched_setaffinity(0, [cpus[0 if role == "ping" else -1]])
    graph = Graph(ping_pong_plan(), "p0" if role == "ping" else "p1", config["session"])
    if role == "echo":
        graph.prepare(["echo"])
        _echo(Node("echo", graph), config, True, keep)
    else:
        _ping(Node("ping", graph), config)
    graph.close()


if __name__ == "__main__":
    _end(sys.argv[1], Path(sys.argv[2]))
