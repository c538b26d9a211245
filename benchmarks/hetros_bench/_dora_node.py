"""A dora-rs Python node for the latency benchmark (``dora run`` starts it).

It keeps its own copy of the ping/echo loop: with the shared loop of ``_roles``
(which drains with 50 ms receive timeouts after the handshake) the dataflow
stalled after the handshake under dora-rs 1.1, and this event-driven one does not.

Its role and configuration come from the environment the dataflow sets; the
protocol matches ``_roles``: a 16-byte prefix in a uint8 arrow array.
"""

import json
import os
import struct
import time

import numpy as np
import pyarrow as pa
from dora import Node

PREFIX = struct.Struct("<qq")
PROBE = -1
STOP = -2


def main() -> None:
    role = os.environ["BENCH_ROLE"]
    with open(os.environ["BENCH_CONFIG"]) as handle:
        cfg = json.load(handle)
    if cfg.get("cpus"):
        os.sched_setaffinity(0, [cfg["cpus"][0 if role == "ping" else 1]])
    node = Node()

    def send(stamp: int, seq: int, payload: np.ndarray) -> None:
        frame = np.empty(PREFIX.size + payload.size, dtype=np.uint8)
        PREFIX.pack_into(frame, 0, stamp, seq)
        frame[PREFIX.size:] = payload
        node.send_output("out", pa.array(frame))

    def recv(timeout: float):  # type: ignore[no-untyped-def]
        event = node.next(timeout=timeout)
        while event is not None and event["type"] != "INPUT":
            if event["type"] == "STOP":
                return None
            event = node.next(timeout=timeout)
        if event is None:
            return None
        arrival = time.monotonic_ns()
        data = event["value"].to_numpy(zero_copy_only=False)
        stamp, seq = PREFIX.unpack_from(data[:PREFIX.size].tobytes())
        return arrival, stamp, seq, data

    result = {}
    if role == "ping":
        payload = np.zeros(cfg["size"], dtype=np.uint8)
        while True:
            send(time.monotonic_ns(), PROBE, payload)
            if recv(0.5) is not None:
                break
        rtt = []
        for seq in range(cfg["warmup"] + cfg["reps"]):
            start = time.monotonic_ns()
            send(start, seq, payload)
            while True:
                got = recv(10.0)
                if got is None:
                    raise SystemExit(f"dora: reply {seq} lost")
                if got[2] == seq:
                    break
            if seq >= cfg["warmup"]:
                rtt.append(time.monotonic_ns() - start)
        send(time.monotonic_ns(), STOP, payload[:0])
        result["rtt_ns"] = rtt
    else:
        one_way = []
        while True:
            got = recv(120.0)
            if got is None:
                break
            arrival, stamp, seq, data = got
            if seq == STOP:
                break
            if seq >= cfg["warmup"]:
                one_way.append(arrival - stamp)
            node.send_output("out", pa.array(data.copy()))
        result["one_way_ns"] = one_way
    with open(cfg[role + "_out"], "w") as handle:
        json.dump(result, handle)


if __name__ == "__main__":
    main()
