"""ReconROS's ping-pong (Fig. 6, Table 3): /send -> copy node -> /recv, round trip per size.

The ping node fills a loaned message (in place: zero copies when the copy node is in
another process), stamps a sequence number into the first bytes, and waits for the
copy to come back; the copy node copies the payload into a message of its own, as
the paper's copy node does. The ping node checks every reply byte for byte.
"""

import json
import time
from pathlib import Path

import numpy as np

from hetros import Node
from hetros.interfaces.std_msgs.msg import UInt8MultiArray


def ping(node: Node) -> None:
    pub = node.create_publisher(UInt8MultiArray, "/send")
    sub = node.create_subscription(UInt8MultiArray, "/recv")
    sizes = node.get_parameter("sizes", [4, 8192, 1 << 20, 6 << 20])
    reps = node.get_parameter("reps", 100)
    warmup = node.get_parameter("warmup", 10)
    rng = np.random.default_rng(0)
    table = []
    for size in sizes:
        pattern = rng.integers(0, 256, size, dtype=np.uint8)
        rtts = []
        for seq in range(warmup + reps):
            msg = pub.loan(data=size)
            msg.data[:] = pattern
            msg.layout.data_offset = seq
            start = time.perf_counter_ns()
            pub.publish(msg)
            reply = sub.take(timeout=10.0)
            elapsed = time.perf_counter_ns() - start
            if reply.layout.data_offset != seq or not np.array_equal(reply.data, pattern):
                raise ValueError(f"reply {seq} of {size} B does not match what was sent")
            if seq >= warmup:
                rtts.append(elapsed / 1000.0)
        row = {"size": size, "mean_us": float(np.mean(rtts)), "std_us": float(np.std(rtts)),
               "p50_us": float(np.percentile(rtts, 50)), "reps": reps}
        table.append(row)
        node.log.info("round trip %9d B: %9.1f ± %7.1f µs (p50 %.1f)", size, row["mean_us"], row["std_us"],
                      row["p50_us"])
    out = node.get_parameter("out", "")
    if out:
        Path(out).write_text(json.dumps(table, indent=1))


def copy(node: Node) -> None:
    pub = node.create_publisher(UInt8MultiArray, "/recv")
    for msg in node.create_subscription(UInt8MultiArray, "/send"):
        reply = pub.loan(data=msg.data.size)
        np.copyto(reply.data, msg.data)
        reply.layout.data_offset = msg.layout.data_offset
        pub.publish(reply)
