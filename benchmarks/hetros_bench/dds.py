"""DDS benchmark: what hetros's DDS transport costs over the cyclonedds binding it runs on.

    python benchmarks/dds.py [--quick] [--out DIR]      (or: hetros bench dds)

One run, ping and pong in two processes pinned to CPUs 0 and 1, Cyclone over UDP loopback
(the binding's bundled library has no shared-memory plugin), payloads 4 B to 6 MiB:

- ``hetros-ros2``: hetros's ROS 2 endpoints (``rt/`` names, ``std_msgs/UInt8MultiArray`` as
  XCDR1 from hetros's codec, written as opaque samples; what `external: ros2:` uses);
- ``hetros-hosts``: hetros's edges between hosts (the channel's bytes framed as one
  ``sequence<octet>``), delivered through the participant's waiting thread as in a graph;
- ``hetros-node``: what users write: two hetros nodes on two hosts of one plan (both on this
  machine), ``pub.publish`` a new message and ``sub.take()`` on each side, through the graph,
  its executor and the hosts' DDS edges;
- ``binding-array``: the raw binding at its fastest, one fixed ``array[uint8, N]`` type per
  size, written and taken in the ping/pong threads themselves;
- ``binding-seq``: the binding's stock path for a ROS-like message, ``sequence[uint8]``;
- ``ddsperf``: Cyclone's native ping/pong (Debian ``cyclonedds-tools``), when installed.

The sender measures the round trip; one-way is half of it. Prints markdown tables, writes
JSON lines and a PNG. Report ratios, not absolute numbers: these machines are noisy.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from ._provenance import provenance
from .latency import SIZE_LABELS, Stats, _table, fmt, log_axes
from .ros1 import wait_all

SIZES = [4, 3 * 1024, 192 * 1024, 3 * 1024 * 1024, 6 * 1024 * 1024]
SYSTEMS = ["hetros-ros2", "hetros-hosts", "hetros-node", "binding-array", "binding-seq", "ddsperf"]


def _reps(system: str, size: int, quick: bool) -> tuple[int, int]:
    if system == "binding-seq" and size >= 1 << 20:
        return (1, 4) if quick else (2, 10)
    if size >= 1 << 20:
        return (3, 15) if quick else (5, 60)
    return (20, 150) if quick else (100, 1000)


# -- the roles -------------------------------------------------------------------------------

class _NodeEndpoint:
    """Two hetros nodes, one per host of a two-host plan, with the edges between them over DDS."""

    def __init__(self, size: int, domain: int, role: str) -> None:
        import numpy as np

        from hetros.msg import registry
        from hetros.plan import LAUNCHER, ChannelPlan, EdgePlan, HostPlan, NodePlan, Plan, TargetPlan
        from hetros.runtime import Graph, Node
        from hetros.transport import QoS

        typename = "std_msgs/msg/UInt8MultiArray"
        qos = QoS(reliability="reliable", history="keep_last", depth=4)
        out, into = ("/bench_ping", "/bench_pong") if role == "ping" else ("/bench_pong", "/bench_ping")
        plan = Plan(
            name="bench_dds", root="", message_paths=(),
            targets={r: TargetPlan(r, "thread", host=r) for r in ("ping", "pong")},
            nodes={r: NodePlan(r, "bench:none", r, publish={f"/bench_{r}": typename},
                               subscribe={f"/bench_{'pong' if r == 'ping' else 'ping'}": typename})
                   for r in ("ping", "pong")},
            channels={f"/bench_{r}": ChannelPlan(f"/bench_{r}", typename, "topic", qos, (r,),
                                                 ("pong" if r == "ping" else "ping",)) for r in ("ping", "pong")},
            edges=(EdgePlan("/bench_ping", "ping", "pong", "dds"), EdgePlan("/bench_pong", "pong", "ping", "dds")),
            hosts={r: HostPlan(r, "127.0.0.1") for r in ("ping", "pong")}, dds_domain=domain,
        ).on_host(role)
        self.graph = Graph(plan, LAUNCHER, f"bench{os.getpid()}", types=registry())
        self.graph.prepare([role])
        node = Node(role, self.graph)
        self.cls = registry().get(typename)
        self.payload = np.zeros(max(size, 1), dtype=np.uint8)
        self.pub = node.create_publisher(self.cls, out)
        self.sub = node.create_subscription(self.cls, into)

    def matched(self) -> bool:
        return not self.graph.wait_for_remote_readers(timeout=0.05)

    def send(self) -> None:
        self.pub.publish(self.cls(data=self.payload))

    def receive(self) -> None:
        self.sub.take(timeout=10)


class _Endpoint:
    """Sends one payload and waits for one, for each system."""

    def __init__(self, system: str, size: int, domain: int, role: str) -> None:
        import numpy as np

        self.system = system
        self.arrived = threading.Event()
        out, into = ("ping", "pong") if role == "ping" else ("pong", "ping")
        self._box: list[Any] = []
        if system.startswith("hetros"):
            from hetros.msg import registry
            from hetros.transport import MessageCodec, QoS
            from hetros.transport.dds import DdsDomain, DdsEdgeReader, DdsEdgeWriter, DdsTopicReader, DdsTopicWriter

            types = registry()
            cls = types.get("std_msgs/msg/UInt8MultiArray")
            self.message = cls(data=np.zeros(max(size, 1), dtype=np.uint8))
            qos = QoS(reliability="reliable", history="keep_last", depth=4)
            self.domain = DdsDomain(domain)
            if system == "hetros-ros2":
                self.writer: Any = DdsTopicWriter(self.domain, types, f"/bench_{out}", cls.__msgtype__, qos)
                self.reader: Any = DdsTopicReader(self.domain, types, f"/bench_{into}", cls.__msgtype__, qos,
                                                  self._deliver)
            else:
                codec = MessageCodec(types, cls.__msgtype__)
                self.writer = DdsEdgeWriter(self.domain, f"hetros/bench/{out}/x", codec, qos)
                self.reader = DdsEdgeReader(self.domain, [f"hetros/bench/{into}/x"], codec, qos, self.arrived.set)
            return
        from cyclonedds.core import InstanceState, Policy, Qos, ReadCondition, SampleState, ViewState, WaitSet
        from cyclonedds.domain import DomainParticipant
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration

        from ._cyclone_types import payload_type, sequence_type

        kind = payload_type(size) if system == "binding-array" else sequence_type()
        data = np.zeros(max(size, 1), dtype=np.uint8)
        self.sample = kind(stamp=0, seq=0, data=data.tolist() if system == "binding-seq" else bytes(data))
        participant = DomainParticipant(domain)
        policies = Qos(Policy.Reliability.Reliable(duration(seconds=10)), Policy.History.KeepLast(4),
                       Policy.DataRepresentation(use_cdrv0_representation=True))
        self.writer = DataWriter(participant, Topic(participant, f"bench_{out}", kind, qos=policies), qos=policies)
        self.reader = DataReader(participant, Topic(participant, f"bench_{into}", kind, qos=policies), qos=policies)
        self.waitset = WaitSet(participant)
        self.waitset.attach(ReadCondition(self.reader, SampleState.Any | ViewState.Any | InstanceState.Any))
        self.participant = participant

    def _deliver(self, message: Any) -> None:
        self._box.append(message)
        self.arrived.set()

    def matched(self) -> bool:
        if self.system.startswith("hetros"):
            return bool(self.writer.matched()) and bool(self.reader.matched())
        return bool(self.writer.get_matched_subscriptions()) and bool(self.reader.get_matched_publications())

    def send(self) -> None:
        if self.system.startswith("hetros"):
            self.writer.write(self.message)
        else:
            self.writer.write(self.sample)

    def receive(self) -> None:
        if self.system == "hetros-ros2":
            while not self._box:
                self.arrived.wait(10)
                self.arrived.clear()
            self._box.pop()
        elif self.system == "hetros-hosts":
            while self.reader.try_take() is None:
                self.arrived.wait(10)
                self.arrived.clear()
        else:
            from cyclonedds.util import duration

            while not self.reader.take(1):
                self.waitset.wait(duration(seconds=10))


def role_main(role: str, system: str, size: int, domain: int, warmup: int, reps: int, out: str, cpu: int) -> int:
    os.sched_setaffinity(0, [cpu])
    endpoint: Any = (_NodeEndpoint(size, domain, role) if system == "hetros-node"
                     else _Endpoint(system, size, domain, role))
    deadline = time.monotonic() + 20
    while not endpoint.matched():
        if time.monotonic() > deadline:
            print(f"{system} {role}: the peer was not matched within 20 s", file=sys.stderr)
            return 1
        time.sleep(0.01)
    rtts = []
    for i in range(warmup + reps):
        if role == "ping":
            start = time.perf_counter_ns()
            endpoint.send()
            endpoint.receive()
            if i >= warmup:
                rtts.append(time.perf_counter_ns() - start)
        else:
            endpoint.receive()
            endpoint.send()
    if role == "ping":
        Path(out).write_text(json.dumps({"rtt_ns": rtts}))
    time.sleep(0.2)  # the last reply leaves before the participant goes
    return 0


# -- ddsperf ---------------------------------------------------------------------------------

def run_ddsperf(size: int, seconds: float) -> float | None:
    """Cyclone's own ping/pong in C, the floor on this machine: the median of its per-second
    medians of one-way latency (ddsperf reports half the round trip), µs."""
    exe = shutil.which("ddsperf")
    if exe is None:
        return None
    env = dict(os.environ, CYCLONEDDS_URI="<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
                                           "</Interfaces><AllowMulticast>false</AllowMulticast></General>"
                                           "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
                                           "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>")
    pong = subprocess.Popen(["taskset", "-c", "1", exe, "-D", str(seconds + 3), "pong"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        ping = subprocess.run(["taskset", "-c", "0", exe, "-D", str(seconds), "ping", "size", str(max(size, 12))],
                              env=env, capture_output=True, text=True, timeout=seconds + 30, check=False)
    finally:
        pong.kill()
        pong.wait()
    # once a second: "... size 3072 mean 37.9us min 16.2us 50% 36.1us 90% 45.6us ..." (one-way)
    medians = sorted(float(m.group(1)) for m in re.finditer(r" 50% ([\d.]+)us", ping.stdout))
    return medians[len(medians) // 2] if medians else None


# -- the run ---------------------------------------------------------------------------------

def measure(system: str, size: int, quick: bool, out: Path) -> dict[str, Any]:
    if system == "ddsperf":
        if shutil.which("ddsperf") is None:
            return {"system": system, "size": size, "error": "ddsperf not installed (Debian cyclonedds-tools)"}
        one_way = run_ddsperf(size, 3 if quick else 8)
        if one_way is None:
            return {"system": system, "size": size, "error": "ddsperf printed no latency (ping and pong did not meet)"}
        return {"system": system, "size": size, "one_way_p50_us": one_way, "rtt_p50_us": 2 * one_way}
    warmup, reps = _reps(system, size, quick)
    domain = 2 + os.getpid() % 100  # Cyclone's ports from domain 102 up are ephemeral ones
    result_file = out / f"dds-{system}-{size}.json"
    procs = [subprocess.Popen([sys.executable, "-m", "hetros_bench.dds", "--role", role, "--system", system,
                               "--size", str(size), "--domain", str(domain), "--warmup", str(warmup),
                               "--reps", str(reps), "--result", str(result_file), "--cpu", str(cpu)],
                              stderr=subprocess.PIPE, text=True)
             for role, cpu in (("pong", 1), ("ping", 0))]
    errors = wait_all(procs, timeout=600)
    if errors:
        return {"system": system, "size": size, "error": " | ".join(errors)}
    rtt = json.loads(result_file.read_text())["rtt_ns"]
    result_file.unlink()
    stats = Stats.of(rtt)
    return {"system": system, "size": size, "one_way_p50_us": stats.p50 / 2, "rtt_p50_us": stats.p50,
            "rtt_p99_us": stats.p99, "reps": reps}


def render(results: list[dict[str, Any]]) -> str:
    by = {(r["system"], r["size"]): r for r in results}

    def p50(size: int, system: str) -> str:
        r = by.get((system, size))
        return "-" if r is None else ("err" if "error" in r else fmt(r["one_way_p50_us"]))

    def ratio(base: str, ours: str, size: int) -> str:
        a, b = by.get((base, size)), by.get((ours, size))
        if not a or not b or "error" in a or "error" in b:
            return "-"
        return f"{b['one_way_p50_us'] / a['one_way_p50_us']:.2f}x"

    lines: list[str] = []
    _table(lines, "One-way latency over DDS (half the round trip), p50 µs", SYSTEMS, SIZES, p50)
    ours = ["hetros-ros2", "hetros-hosts", "hetros-node"]
    _table(lines, "hetros over the raw binding (time ratio; target <= 1.3x)", ours, SIZES,
           lambda size, system: ratio("binding-array", system, size))
    _table(lines, "The binding's stock sequence<uint8> path over hetros (speed-up; target >= 10x from 196 kB)",
           ours, SIZES, lambda size, system: ratio(system, "binding-seq", size))
    errors = [r for r in results if "error" in r]
    if errors:
        lines += ["", "### Missing or failed", ""]
        lines += [f"- {r['system']} at {SIZE_LABELS.get(r['size'], r['size'])}: {r['error'][:200]}" for r in errors]
    return "\n".join(lines)


def plot(results: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for system in SYSTEMS:
        points = [(r["size"], r["one_way_p50_us"]) for r in results if r["system"] == system and "error" not in r]
        if points:
            ax.plot(*zip(*points, strict=True), marker="o", label=system)
    log_axes(ax, "DDS one-way latency (p50)", "µs")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    parser.add_argument("--out", default="out/bench", help="folder for dds.jsonl, dds.md, dds.png")
    parser.add_argument("--role", choices=["ping", "pong"], help=argparse.SUPPRESS)
    parser.add_argument("--system", help=argparse.SUPPRESS)
    parser.add_argument("--size", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--domain", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--warmup", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--reps", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--result", help=argparse.SUPPRESS)
    parser.add_argument("--cpu", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.role:
        return role_main(args.role, args.system, args.size, args.domain, args.warmup, args.reps, args.result,
                         args.cpu if (os.cpu_count() or 1) > args.cpu else 0)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = []
    for system in SYSTEMS:
        for size in SIZES:
            result = measure(system, size, args.quick, out)
            results.append(result)
            status = result.get("error", "")[:120] or f"one-way p50 {result['one_way_p50_us']:.1f} µs"
            print(f"[bench] {system:14} {SIZE_LABELS.get(size, size):>8}: {status}", flush=True)
    report = render(results)
    print()
    print(report)
    (out / "dds.md").write_text(provenance() + "\n\n" + report + "\n")
    (out / "dds.jsonl").write_text("".join(json.dumps(r) + "\n" for r in results))
    plot(results, out / "dds.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
