"""Where the time of one shared-memory hop goes, without wake-ups (both sides in one process).

    python benchmarks/profile_shm.py [payload bytes]

Prints microseconds per publish (loaned and plain), per take, and for rosbags'
(de)serialization of the non-array part of a sensor_msgs/Image. These are the
Python costs that remain once the adaptive spin has removed the wake-up.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable

import numpy as np

from hetros.bench._roles import HetrosEndpoint, _hetros_plan
from hetros.msg import registry
from hetros.runtime import Graph
from hetros.transport import remove_session_segments

N = 3000


def per_call(fn: Callable[[], object]) -> float:
    for _ in range(200):
        fn()
    start = time.perf_counter()
    for _ in range(N):
        fn()
    return (time.perf_counter() - start) / N * 1e6


def main() -> None:
    size = int(sys.argv[1]) if len(sys.argv) > 1 else 4
    session = f"{os.getpid()}xprofile"
    publisher_graph = Graph(_hetros_plan(16), "p0", session)
    subscriber_graph = Graph(_hetros_plan(16), "p1", session)
    subscriber_graph.prepare(["echo"])
    echo = HetrosEndpoint("echo", subscriber_graph, loaned=True)
    ping = HetrosEndpoint("ping", publisher_graph, loaned=True)
    payload = np.zeros(size, np.uint8)
    for loaned in (True, False):
        ping.loaned = loaned
        send = take = 0.0
        for _ in range(N):
            a = time.perf_counter()
            ping.send(1, 1, payload)
            b = time.perf_counter()
            echo.sub.try_take()
            c = time.perf_counter()
            send, take = send + b - a, take + c - b
        kind = "loaned" if loaned else "plain"
        print(f"{size} B {kind:6} publish {send / N * 1e6:6.1f} us   take {take / N * 1e6:6.1f} us")
    types = registry()
    image = types.get("sensor_msgs/msg/Image")(data=np.zeros(size, np.uint8))
    raw = types.serialize(image)
    codec = types.codec("sensor_msgs/msg/Image")
    buffer = memoryview(bytearray(len(raw)))
    body = raw[4:].toreadonly()
    print(f"{size} B Image: generated encode {per_call(lambda: codec.encode(image, buffer)):5.1f} us, "
          f"decode {per_call(lambda: codec.decode(body)):5.1f} us; "
          f"rosbags serialize {per_call(lambda: types.serialize(image)):5.1f} us, "
          f"deserialize {per_call(lambda: types.deserialize(raw, image.__msgtype__)):5.1f} us")
    ping.close()
    echo.close()
    remove_session_segments(session)


if __name__ == "__main__":
    main()
