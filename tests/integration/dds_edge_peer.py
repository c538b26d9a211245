"""One side of the bounded DDS edge test, run as its own process:
``python dds_edge_peer.py reader|writer DOMAIN SECONDS OUT``.

The reader opens a keep_all and a keep_last edge and never takes; the writer publishes
1 MB samples on both at 100 Hz for SECONDS and records what publishing did.
"""

from __future__ import annotations

import json
import os
import sys
import threading
import time
from pathlib import Path

import numpy as np

from hetros import PublishTimeoutError
from hetros.interfaces.std_msgs.msg import UInt8MultiArray
from hetros.msg import registry
from hetros.transport import MessageCodec, QoS
from hetros.transport.dds import DdsDomain, DdsEdgeReader, DdsEdgeWriter

TYPE = "std_msgs/msg/UInt8MultiArray"
QOS = {"all": QoS(depth=4, publish_timeout=1.0), "last": QoS(history="keep_last", depth=4)}


def rss() -> int:
    with open(f"/proc/{os.getpid()}/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def main() -> None:
    role, domain_id, seconds, out = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), Path(sys.argv[4])
    domain = DdsDomain(domain_id)
    codec = MessageCodec(registry(), TYPE)
    if role == "reader":
        readers = [DdsEdgeReader(domain, [f"bounded/{name}"], codec, qos, lambda: None) for name, qos in QOS.items()]
        samples, matched = [], [0, 0]
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            samples.append(rss())
            matched = [max(m, r.matched()) for m, r in zip(matched, readers, strict=True)]
            time.sleep(1.0)
        cpu = os.times()
        out.write_text(json.dumps({"rss": samples, "matched": matched, "cpu": cpu.user + cpu.system}))
        return
    writers = {name: DdsEdgeWriter(domain, f"bounded/{name}", codec, qos) for name, qos in QOS.items()}
    deadline = time.monotonic() + 10
    while any(w.matched() == 0 for w in writers.values()) and time.monotonic() < deadline:
        time.sleep(0.05)
    message = UInt8MultiArray(data=np.ones(1_000_000, np.uint8))
    report: dict[str, float | None] = {"sent_all": 0, "timeouts_all": 0, "sent_last": 0, "first_timeout_at": None}
    started = time.monotonic()

    def publish(name: str) -> None:  # 100 Hz, each edge in a thread of its own as nodes would
        while (tick := time.monotonic()) - started < seconds:
            try:
                writers[name].write(message)
                report[f"sent_{name}"] = (report[f"sent_{name}"] or 0) + 1
            except PublishTimeoutError:
                report["timeouts_all"] = (report["timeouts_all"] or 0) + 1
                if report["first_timeout_at"] is None:
                    report["first_timeout_at"] = time.monotonic() - started
            time.sleep(max(0.0, 0.01 - (time.monotonic() - tick)))

    threads = [threading.Thread(target=publish, args=(name,)) for name in QOS]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    out.write_text(json.dumps(report))


if __name__ == "__main__":
    main()
