"""What a tap costs a publisher: idle (nobody looks), looked at by hz/bw (sizes and stamps), and by
echo/record (encoded bytes), against a plain copy of the message for scale.

    .venv/bin/python benchmarks/taps.py [--count 20000] [--out out/bench]

Each row publishes on one topic of an in-process graph (no subscriber, so the publish path
itself is what is timed) in a tight loop, the way a node's ``publish`` runs; a thread drains the
sink as ``hetros topic echo``'s control thread does. Medians of 5 runs, in ns per publish, and
ratios to the idle tap; the machines are noisy, so read the ratios.
"""

from __future__ import annotations

import argparse
import copy
import json
import statistics
import threading
import time
from pathlib import Path
from typing import Any

from hetros.interfaces.sensor_msgs.msg import Image
from hetros.interfaces.std_msgs.msg import String
from hetros.runtime import Node
from hetros.runtime._taps import TapSink
from hetros.transport import MessageCodec
from hetros_bench._provenance import provenance


def _publish_ns(make: Any, typename: str, mode: str, count: int) -> float:
    node = Node(f"bench_{mode}")
    pub = node.create_publisher(type(make()), "/tapped")
    codec = MessageCodec(node.graph.types, typename)
    sink = None
    if mode != "idle":
        sink = TapSink(codec, data=mode == "echo")
        node.graph.tap_point("/tapped", typename).attach(sink)
        def drain() -> None:  # as the control thread: each encoded message sent, its buffer given back
            while not sink.closed:
                taken = sink.take(0.05)
                if taken is not None and mode == "echo":
                    sink.give_back(taken[1])
        drained = threading.Thread(target=drain, daemon=True)
        drained.start()
    messages = [make() for _ in range(count)]
    start = time.perf_counter_ns()
    for message in messages:
        pub.publish(message)
    elapsed = time.perf_counter_ns() - start
    if sink is not None:
        node.graph.tap_point("/tapped", typename).detach(sink)
    node.close()
    return elapsed / count


def _copy_ns(make: Any, count: int) -> float:
    messages = [make() for _ in range(count)]
    start = time.perf_counter_ns()
    for message in messages:
        copy.copy(message)
    return (time.perf_counter_ns() - start) / count


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=20000)
    parser.add_argument("--out", default="out/bench")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cases = {
        "String (13 B)": (lambda: String(data="hello world 1"), "std_msgs/msg/String", args.count),
        "Image 640x480 rgb8": (lambda: Image(height=480, width=640, encoding="rgb8", step=1920,
                                             data=bytes(640 * 480 * 3)), "sensor_msgs/msg/Image", args.count // 100),
    }
    rows = []
    for label, (make, typename, count) in cases.items():
        figures = {"plain copy.copy": statistics.median(_copy_ns(make, count) for _ in range(5))}
        for mode in ("idle", "hz/bw", "echo"):
            figures[f"publish, tap {mode}"] = statistics.median(
                _publish_ns(make, typename, mode, count) for _ in range(5))
        idle = figures["publish, tap idle"]
        for system, ns in figures.items():
            rows.append({"message": label, "system": system, "ns_per_publish": ns, "ratio_to_idle": ns / idle})
    print(f"{'message':<20} {'system':<22} {'ns/publish':>12} {'x idle':>8}")
    for row in rows:
        print(f"{row['message']:<20} {row['system']:<22} {row['ns_per_publish']:>12.0f} {row['ratio_to_idle']:>8.2f}")
    (out / "taps.json").write_text(json.dumps({"provenance": provenance(), "rows": rows}, indent=1))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, len(cases), figsize=(11, 4))
    for axis, label in zip(axes, cases, strict=True):
        mine = [r for r in rows if r["message"] == label]
        axis.barh([r["system"] for r in mine], [r["ratio_to_idle"] for r in mine])
        axis.set_title(label)
        axis.set_xlabel("time per publish / idle tap")
    figure.tight_layout()
    figure.savefig(out / "taps.png")
    print(f"wrote {out / 'taps.json'} and {out / 'taps.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
