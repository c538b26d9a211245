"""Throughput and idle-CPU roles of the benchmark (``python -m hetros_bench._throughput``)."""

from __future__ import annotations

import json
import os
import sys
import threading
import time
from pathlib import Path

import numpy as np

from ._roles import STOP, open_endpoint


def publisher(system: str, cfg: dict[str, object]) -> None:
    endpoint = open_endpoint(system, "ping", dict(cfg, system=system))
    size = int(cfg["size"])  # type: ignore[call-overload]
    payload = np.zeros(size, dtype=np.uint8) if system.startswith("hetros") else bytes(size)
    endpoint.send(time.monotonic_ns(), -1, payload)
    time.sleep(0.5)
    end = time.monotonic() + float(cfg["seconds"])  # type: ignore[arg-type]
    seq = 0
    while time.monotonic() < end:
        # every byte written for every message (a loaned payload the publisher never fills is
        # not throughput): the loaned rows copy it in, the plain rows copy it out
        endpoint.send(time.monotonic_ns(), seq, payload)
        seq += 1
    endpoint.send(time.monotonic_ns(), STOP, payload[:0])
    time.sleep(0.5)


def subscriber(system: str, cfg: dict[str, object]) -> dict[str, float]:
    endpoint = open_endpoint(system, "echo", dict(cfg, system=system))
    count = 0
    first = last = 0
    while True:
        got = endpoint.recv(60.0)
        if got is None:
            break
        _stamp, seq, data = got
        payload = endpoint.payload(data)
        if len(payload):
            np.frombuffer(payload, np.uint8).max()  # every byte read, on every system
        del payload
        del data, got
        if seq == STOP:
            break
        if seq < 0:
            continue
        now = time.monotonic_ns()
        if count == 0:
            first = now
        last = now
        count += 1
    elapsed = (last - first) / 1e9
    return {"messages": count, "seconds": elapsed, "rate": (count - 1) / elapsed if elapsed > 0 else 0.0}


def idle_cpu(period: float, seconds: float) -> dict[str, float]:
    from hetros import Node
    from hetros.msg import registry
    from hetros.runtime import Graph

    String = registry().get("std_msgs/msg/String")

    graph = Graph.standalone()
    node = Node("idle", graph)
    ticks = [0]
    if period > 0:
        node.create_timer(period, lambda: ticks.__setitem__(0, ticks[0] + 1))
    else:
        node.create_subscription(String, "/nothing", lambda m: None)
    threading.Timer(seconds, graph.shutdown).start()
    time.sleep(0.2)
    cpu0, wall0 = time.process_time(), time.monotonic()
    node.spin()
    cpu, wall = time.process_time() - cpu0, time.monotonic() - wall0
    return {"cpu_percent": 100.0 * cpu / wall, "ticks_per_s": ticks[0] / wall, "seconds": wall}


def receiving_cpu(hz: float, seconds: float) -> dict[str, float]:
    """A take-loop subscriber receiving ``hz`` messages/s from a timer node (one process, both counted)."""
    from hetros import Node, ShutdownError
    from hetros.msg import registry
    from hetros.runtime import Graph

    Int32 = registry().get("std_msgs/msg/Int32")
    graph = Graph.standalone()
    sub = Node("sub", graph).create_subscription(Int32, "/t")
    publisher_node = Node("pub", graph)
    pub = publisher_node.create_publisher(Int32, "/t")
    publisher_node.create_timer(1.0 / hz, lambda: pub.publish(Int32(data=1)))
    received = [0]

    def take_loop() -> None:
        try:
            while True:
                sub.take()
                received[0] += 1
        except ShutdownError:
            return

    taker = threading.Thread(target=take_loop)
    taker.start()
    threading.Timer(seconds, graph.shutdown).start()
    time.sleep(0.2)
    cpu0, wall0 = time.process_time(), time.monotonic()
    publisher_node.spin()
    cpu, wall = time.process_time() - cpu0, time.monotonic() - wall0
    taker.join()
    return {"cpu_percent": 100.0 * cpu / wall, "received_per_s": received[0] / wall, "seconds": wall}


def main() -> None:
    system, role = sys.argv[1], sys.argv[2]
    if system == "cpu":
        print(json.dumps(idle_cpu(float(sys.argv[2]), float(sys.argv[3]))))
        return
    if system == "cpu-receiving":
        print(json.dumps(receiving_cpu(float(sys.argv[2]), float(sys.argv[3]))))
        return
    cfg = json.loads(Path(sys.argv[3]).read_text())
    if cfg.get("fds"):
        cfg["fds"] = {k: tuple(v) for k, v in cfg["fds"].items()}
    if cfg.get("cpus"):
        os.sched_setaffinity(0, [cfg["cpus"][0 if role == "pub" else 1]])
    if role == "pub":
        publisher(system, cfg)
    else:
        Path(cfg["echo_out"]).write_text(json.dumps(subscriber(system, cfg)))
    os._exit(0)


if __name__ == "__main__":
    main()
