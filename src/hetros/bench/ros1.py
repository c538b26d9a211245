"""ROS 1 benchmark: one-way latency over TCPROS between rospy and hetros nodes, both ways.

    python benchmarks/ros1.py [--quick] [--rounds N] [--settle-us US] [--gap-ms MS] [--out DIR]
    (or: hetros bench ros1)

Four pairs, sender -> receiver, in one run through one Debian rosmaster, the sender pinned
to CPU 0 and the receiver to CPU 1: rospy -> rospy, rospy -> hetros, hetros -> rospy and
hetros -> hetros. The run goes round every size and pair ``--rounds`` times (3) and pools
each pair's samples: absolute times here drift by 2x within minutes, and interleaving
lets every pair meet the same drift, so the ratios compare like with like.
hetros's side is what a user writes: nodes on ``kind: ros1`` targets
started by ``hetros launch``, the receiver a subscription callback that publishes the data
back. One-way latency is measured by the receiver (the sender's stamp in the payload, one
monotonic clock); the round trip by the sender. Prints markdown tables, writes JSON lines
and a PNG plot. Report ratios, not absolute numbers.

Every sender, after each reply, lets ``--settle-us`` (50 µs) pass, awake, before it stamps
the next message. Without it a fast sender's next message lands while a rospy echo is
still busy with its reply (its publisher's writer thread shares the echo's CPU), and the
one-way time of that message then holds the echo's leftover work: measured here, a rospy
receiver got hetros's messages 17-22 µs later than rospy's, by as much as hetros's sender
was quicker, and 30 µs of settling already removed that. ``--settle-us 0`` measures
back-to-back exchanges; ``--gap-ms`` sleeps instead (isolated messages: every receiver then
wakes from idle).

``--steady-malloc`` gives every process of the run (rospy's and hetros's alike)
``GLIBC_TUNABLES`` that keep glibc's malloc from mapping and unmapping large buffers per
message (``STEADY_MALLOC``). By default, as users run rospy, a rospy receiver lands per
process and by chance in one of two modes for 196 kB messages: its buffers come from a
heap that stays mapped (about 110-150 µs from send to callback), or from fresh pages that
fault in every time (230-300 µs; page faults are slow on these VMs). Over five runs here
either sender met either mode, so a pair's figure can hold its receiver's luck; steady
malloc removes the luck (and makes rospy -> rospy about 1.7x faster at 3 MiB and above).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from .latency import SIZE_LABELS, Bench, Result, Stats, _table, fmt, log_axes

SIZES = [4, 3 * 1024, 192 * 1024, 3 * 1024 * 1024, 6 * 1024 * 1024]
# buffers up to 32 MiB from the heap, and the heap never trimmed below 128 MiB
STEADY_MALLOC = "glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=134217728"
PAIRS = [("rospy", "rospy"), ("rospy", "hetros"), ("hetros", "rospy"), ("hetros", "hetros")]
ROSPY_PEER = Path(__file__).resolve().parent / "_rospy_peer.py"


def pair_name(sender: str, receiver: str) -> str:
    return f"{sender}->{receiver}"


Samples = tuple[list[int], list[int]]


class Ros1Bench(Bench):
    def run_ros1_pair(self, sender: str, receiver: str, size: int, gap: float = 0.0, rounds: int = 1,
                      settle: float = 0.0) -> Samples:
        """One run of a pair: (one-way, round-trip) samples in ns, a ``rounds``-th of the repetitions.

        Raises BenchError with the processes' last words when the run fails.
        """
        name = pair_name(sender, receiver)
        cfg, path = self.config(name, size)
        cfg["gap_s"] = gap
        cfg["settle_s"] = settle
        cfg["reps"] = max(cfg["reps"] // rounds, 10)
        path.write_text(json.dumps(cfg))
        cpus = self.cpus or []
        nodes: dict[str, dict[str, Any]] = {}
        procs: list[subprocess.Popen[str]] = []
        for role, kind, cpu in (("echo", receiver, cpus[1:2]), ("ping", sender, cpus[0:1])):
            if kind == "hetros":
                nodes[role] = {"cpus": cpu, "parameters": {"size": size, "warmup": cfg["warmup"], "gap_s": gap,
                                                           "settle_s": settle,
                                                           "reps": cfg["reps"], "out": cfg[f"{role}_out"]}}
        project = self.tmp / f"{name}-{size}.yaml"
        project.write_text(_project(nodes))
        if nodes:
            procs.append(subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project)],
                                          env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True))
        for role, kind in (("echo", receiver), ("ping", sender)):
            if kind == "rospy":
                procs.append(subprocess.Popen(["/usr/bin/python3", str(ROSPY_PEER), role, str(path)], env=self.env,
                                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True))
        errors = wait_all(procs, timeout=600)
        if errors:
            raise BenchError("\n".join(errors))
        try:
            rtt = json.loads(Path(cfg["ping_out"]).read_text())["rtt_ns"]
            one_way = json.loads(Path(cfg["echo_out"]).read_text())["one_way_ns"]
        except (OSError, ValueError, KeyError) as exc:
            raise BenchError(f"no result: {exc}") from None
        return one_way, rtt


class BenchError(Exception):
    """A benchmark run that gave no samples (its text goes into the report, the run goes on)."""


def wait_all(procs: list[subprocess.Popen[str]], timeout: float) -> list[str]:
    """Wait for every process; the first that fails (or the timeout) stops the others. Their errors."""
    deadline = time.monotonic() + timeout
    while any(p.poll() is None for p in procs):
        if time.monotonic() > deadline or any(p.returncode not in (None, 0) for p in procs):
            for proc in procs:
                if proc.poll() is None:
                    proc.kill()
            break
        time.sleep(0.05)
    return [(p.communicate()[1] or "").strip()[-400:] or f"exit code {p.returncode}"
            for p in procs if p.wait() != 0]


def _project(nodes: dict[str, dict[str, Any]]) -> str:
    """A project with the hetros roles, each alone on a ``kind: ros1`` target pinned to its CPU."""
    lines = ["name: bench_ros1", "targets:"]
    lines += [f"  {role}: {{kind: ros1, cpus: {spec['cpus']}}}" for role, spec in nodes.items()]
    lines.append("nodes:")
    topics = {"ping": ("/bench_send", "/bench_recv"), "echo": ("/bench_recv", "/bench_send")}
    for role, spec in nodes.items():
        out, into = topics[role]
        lines += [f"  {role}:", f"    run: hetros.bench._ros1_nodes:{role}", f"    target: {role}",
                  "    required: true", f"    publish: {{{out}: std_msgs/msg/UInt8MultiArray}}",
                  f"    subscribe: {{{into}: std_msgs/msg/UInt8MultiArray}}",
                  f"    parameters: {json.dumps(spec['parameters'])}"]
    lines.append("topics:")
    lines += [f"  {topic}: {{reliability: reliable, history: keep_last, depth: 16}}"
              for topic in ("/bench_send", "/bench_recv")]
    return "\n".join(lines) + "\n"


def render(results: list[Result], sizes: list[int], missing: str, malloc: str = "") -> str:
    by = {(r.system, r.size): r for r in results}
    names = [pair_name(*pair) for pair in PAIRS]

    def stat(size: int, name: str) -> str:
        r = by.get((name, size))
        if r is None or r.one_way is None:
            return "err" if r is not None and r.error else "-"
        return f"{fmt(r.one_way.p50)} ({fmt(r.one_way.p99)})"

    def speedup(size: int, name: str) -> str:
        base, r = by.get(("rospy->rospy", size)), by.get((name, size))
        if base is None or r is None or base.one_way is None or r.one_way is None:
            return "-"
        return f"{base.one_way.p50 / r.one_way.p50:.2f}x"

    lines: list[str] = []
    _table(lines, "One-way latency over TCPROS, sender -> receiver, p50 µs (p99)", names, sizes, stat)
    _table(lines, "Speed-up over rospy -> rospy (rospy p50 / pair p50; target: hetros -> hetros >= 2x, "
                  "every pair with hetros >= 1x)", names[1:], sizes, speedup)
    lines += ["", f"Every process ran with GLIBC_TUNABLES={malloc} (--steady-malloc)" if malloc else
              "Every process ran with glibc's default malloc"]
    if missing:
        lines += ["", f"Missing: {missing}"]
    errors = [r for r in results if r.error]
    if errors:
        lines += ["", "### Errors", ""]
        lines += [f"- {r.system} at {SIZE_LABELS.get(r.size, r.size)}: {r.error.splitlines()[-1][:200]}"
                  for r in errors]
    return "\n".join(lines)


def plot(results: list[Result], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for sender, receiver in PAIRS:
        name = pair_name(sender, receiver)
        points = [(r.size, r.one_way.p50) for r in results if r.system == name and r.one_way is not None]
        if points:
            ax.plot(*zip(*points, strict=True), "-o" if "hetros" in name else "--.", label=name)
    log_axes(ax, "one-way latency over TCPROS", "µs, p50")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    parser.add_argument("--out", default="out/bench", help="folder for ros1.jsonl, ros1.md, ros1.png")
    parser.add_argument("--rounds", type=int, default=None,
                        help="interleaved rounds over every pair and size, their samples pooled (default 3, "
                             "--quick 1): machine drift during the run then weighs on every pair alike")
    parser.add_argument("--settle-us", type=float, default=50.0,
                        help="time every sender lets pass, awake, after each reply before the next message "
                             "(default 50: the receiver has finished its reply); 0 for back-to-back exchanges")
    parser.add_argument("--steady-malloc", action="store_true",
                        help="every process keeps large buffers mapped (GLIBC_TUNABLES): no per-process "
                             "luck of the allocator in a receiver (see the module's help)")
    parser.add_argument("--gap-ms", type=float, default=0.0,
                        help="pause of the sender after each reply: 0 (default) measures back-to-back exchanges, "
                             "a few ms isolated messages (every receiver then wakes from idle)")
    args = parser.parse_args(argv)
    cpus = None if (os.cpu_count() or 1) < 2 else [0, 1]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    bench = Ros1Bench(out, args.quick, cpus)
    if args.steady_malloc:
        bench.env["GLIBC_TUNABLES"] = STEADY_MALLOC
    results: list[Result] = []
    missing = bench.available("rospy")
    rounds = args.rounds or (1 if args.quick else 3)
    samples: dict[tuple[str, int], Samples] = {}
    failed: dict[tuple[str, int], str] = {}
    try:
        if missing:
            print(f"[bench] rospy: missing: {missing}", flush=True)
        else:
            for round_number in range(1, rounds + 1):
                for size in SIZES:
                    for sender, receiver in PAIRS:
                        key = (pair_name(sender, receiver), size)
                        if key in failed:
                            continue
                        try:
                            one_way, rtt = bench.run_ros1_pair(sender, receiver, size, args.gap_ms / 1000.0, rounds,
                                                                 args.settle_us / 1e6)
                        except BenchError as exc:
                            failed[key] = str(exc)
                            status = str(exc).splitlines()[-1][:120]
                        else:
                            pooled = samples.setdefault(key, ([], []))
                            pooled[0].extend(one_way)
                            pooled[1].extend(rtt)
                            status = f"p50 {Stats.of(one_way).p50:.1f} µs"
                        print(f"[bench] round {round_number}/{rounds} {key[0]:16} "
                              f"{SIZE_LABELS.get(size, size):>8}: {status}", flush=True)
    finally:
        bench.close()
    for size in SIZES:
        for sender, receiver in PAIRS:
            key = (pair_name(sender, receiver), size)
            if key in failed:
                results.append(Result(key[0], size, error=failed[key]))
            elif key in samples:
                results.append(Result(key[0], size, Stats.of(samples[key][0]), Stats.of(samples[key][1])))
    report = render(results, SIZES, missing, STEADY_MALLOC if args.steady_malloc else "")
    print()
    print(report)
    (out / "ros1.md").write_text(report + "\n")
    with (out / "ros1.jsonl").open("w") as handle:
        for r in results:
            handle.write(json.dumps({"pair": r.system, "size": r.size, "error": r.error,
                                     "one_way_us": r.one_way.__dict__ if r.one_way else None,
                                     "rtt_us": r.rtt.__dict__ if r.rtt else None}) + "\n")
    if results:
        plot(results, out / "ros1.png")
    print(f"\nwrote {out / 'ros1.md'}, {out / 'ros1.jsonl'}, {out / 'ros1.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
