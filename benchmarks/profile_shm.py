"""Where the time of one shared-memory hop goes, without wake-ups (both sides in one process).

    python benchmarks/profile_shm.py [payload bytes]

Prints microseconds per publish (loaned and plain) and per take of a ``sensor_msgs/Image``,
and the generated codec's encode/decode beside rosbags'. These are the Python costs that
remain once the adaptive spin has removed the wake-up.

The machines this runs on are noisy in phases of seconds (the same loop measured 7 µs and
12 µs a minute apart), so variants are interleaved in short rounds and each reports its
fastest round: noise only ever adds time.
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

N = 1000
ROUNDS = int(os.environ.get("ROUNDS", "25"))


def fastest_round(variants: dict[str, Callable[[], object]]) -> dict[str, float]:
    """Microseconds per call of each variant: the fastest of ROUNDS interleaved rounds."""
    best = dict.fromkeys(variants, float("inf"))
    for _ in range(ROUNDS):
        for name, fn in variants.items():
            start = time.perf_counter()
            for _ in range(N):
                fn()
            best[name] = min(best[name], (time.perf_counter() - start) / N * 1e6)
    return best


def main() -> None:
    size = int(sys.argv[1]) if len(sys.argv) > 1 else 4
    session = f"{os.getpid()}xprofile"
    publisher_graph = Graph(_hetros_plan(16), "p0", session)
    subscriber_graph = Graph(_hetros_plan(16), "p1", session)
    subscriber_graph.prepare(["echo"])
    echo = HetrosEndpoint("echo", subscriber_graph, loaned=True)
    plain = HetrosEndpoint("ping", publisher_graph, loaned=False)
    payload = np.zeros(size, np.uint8)
    payload.flags.writeable = False  # the user's frame, handed over without a copy in a process

    def publish(loaned: bool) -> Callable[[], object]:
        def once() -> None:
            plain.loaned = loaned
            plain.send(1, 1, payload)
            echo.sub.try_take()
        return once

    def take_only() -> None:
        echo.sub.try_take()

    try:
        hop = fastest_round({"loaned": publish(True), "plain": publish(False), "empty take": take_only})
        for kind in ("plain", "loaned"):
            print(f"{size} B {kind:6} publish + take: {hop[kind]:6.1f} us per hop")
        types = registry()
        image = types.get("sensor_msgs/msg/Image")(data=np.zeros(size, np.uint8))
        raw = types.serialize(image)
        codec = types.codec("sensor_msgs/msg/Image")
        buffer = memoryview(bytearray(len(raw)))
        body = raw[4:].toreadonly()
        codecs = fastest_round({
            "encode": lambda: codec.encode(image, buffer), "decode": lambda: codec.decode(body),
            "serialize": lambda: types.serialize(image),
            "deserialize": lambda: types.deserialize(raw, image.__msgtype__),
        })
        print(f"{size} B Image: generated encode {codecs['encode']:5.1f} us, decode {codecs['decode']:5.1f} us; "
              f"rosbags serialize {codecs['serialize']:5.1f} us, deserialize {codecs['deserialize']:5.1f} us")
    finally:
        plain.close()
        echo.close()
        remove_session_segments(session)


if __name__ == "__main__":
    main()
