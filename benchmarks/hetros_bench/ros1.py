"""ROS 1 benchmark: one-way latency over TCPROS between rospy and hetros nodes, both ways.

    python benchmarks/ros1.py [--quick] [--rounds N] [--settle-us US] [--gap-ms MS] [--steady-malloc] [--out DIR]
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

One receiver process serves both senders at once, which take turns of eight exchanges
(through FIFOs the bench drives; who goes first alternates; the first exchange of a turn
is not measured). That matters for rospy: per connection and by chance, a rospy
receiver's 196 kB buffers come from a heap that stays mapped or from pages returned to
the kernel after each message and faulted in again (about 100 µs more; page faults are
slow on these VMs); rospy reads each connection in a thread of its own, and glibc gives
threads arenas of their own. With a receiver process per pair, a hetros -> rospy figure held its receiver's luck
against rospy -> rospy's (0.63x once in five runs, 1.06-1.10x otherwise); with both
senders in turn at the same receiver, the machine's drift and the process's state are the
same for both, and only the connection's luck remains (see the README's figures).

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
message (``STEADY_MALLOC``): the fast mode for everyone (it makes rospy -> rospy about
1.7x faster at 3 MiB and above). The default is glibc's, as users run rospy.
"""

from __future__ import annotations

import argparse
import errno
import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from hetros import Error

from ._provenance import provenance
from ._ros1_protocol import measured, reply_topic
from .latency import SIZE_LABELS, Bench, Result, Stats, _table, fmt, log_axes, parse_sizes

SIZES = [4, 3 * 1024, 192 * 1024, 3 * 1024 * 1024, 6 * 1024 * 1024]
# buffers up to 32 MiB from the heap, and the heap never trimmed below 128 MiB
STEADY_MALLOC = "glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=134217728"
PAIRS = [("rospy", "rospy"), ("rospy", "hetros"), ("hetros", "rospy"), ("hetros", "hetros")]
# exchanges a sender makes per turn; the first of each is not measured (the receiver wakes
# from the other sender's turn), the rest run back to back as with one sender
TURN = 8
ROSPY_PEER = Path(__file__).resolve().parent / "_rospy_peer.py"


def pair_name(sender: str, receiver: str) -> str:
    return f"{sender}->{receiver}"


Samples = tuple[list[int], list[int]]


class Ros1Bench(Bench):
    def run_receiver(self, receiver: str, senders: list[str], size: int, gap: float = 0.0, rounds: int = 1,
                     settle: float = 0.0) -> dict[str, Samples | BenchError]:
        """One receiver process serving the senders at once, in turns: per sender, (one-way,
        round-trip) samples in ns (a ``rounds``-th of the repetitions), or the BenchError of
        the run.

        Every sender meets the same receiver process at the same moments, so a comparison of
        senders holds no luck of that process (where its allocator put its buffers, see the
        module's help) and no drift of the machine. The senders take turns of ``TURN``
        exchanges through two FIFOs each ("go" from here, "done" back); who goes first
        alternates (A B B A A B ...).
        """
        cfg, path = self.config(f"to-{receiver}", size)
        tags = {sender: tag for tag, sender in enumerate(senders, start=1)}
        cfg.update(gap_s=gap, settle_s=settle, reps=max(cfg["reps"] // rounds, 2 * TURN), serve=True,
                   tags=list(tags.values()), block=TURN)
        path.write_text(json.dumps(cfg))
        echo_out = Path(cfg["echo_out"])
        echo_out.unlink(missing_ok=True)  # an earlier round's file has the same name
        procs: dict[str, subprocess.Popen[str]] = {}
        go: dict[str, int] = {}
        done: dict[str, int] = {}
        outs: dict[str, Path] = {}
        run = self.tmp / f"{receiver}-{size}-{os.urandom(3).hex()}"
        try:
            procs["echo"] = self._start("echo", receiver, cfg, path)
            for sender, tag in tags.items():
                fifos = [Path(f"{run}-{tag}-go"), Path(f"{run}-{tag}-done")]
                for fifo in fifos:
                    os.mkfifo(fifo)
                done[sender] = os.open(fifos[1], os.O_RDONLY | os.O_NONBLOCK)
                outs[sender] = Path(f"{run}-{tag}-ping.json")
                ping_cfg = dict(cfg, tag=tag, turns=[str(f) for f in fifos], ping_out=str(outs[sender]))
                ping_path = Path(f"{run}-{tag}.json")
                ping_path.write_text(json.dumps(ping_cfg))
                procs[sender] = self._start("ping", sender, ping_cfg, ping_path)
            for sender, tag in tags.items():
                _await_byte(done[sender], procs, f"the {sender} sender to connect", 90.0)
                go[sender] = _open_fifo_writer(Path(f"{run}-{tag}-go"), procs)
            total = cfg["warmup"] + cfg["reps"]
            for turn in range(-(-total // TURN)):
                for sender in senders if turn % 2 == 0 else senders[::-1]:
                    os.write(go[sender], b"g")
                    _await_byte(done[sender], procs, f"turn {turn} of the {sender} sender", 120.0)
            for sender in senders:
                if procs[sender].wait(timeout=60) != 0:
                    raise BenchError(_last_words(procs[sender]))
            expected = sum(measured(count, cfg["warmup"], TURN) for count in range(total))
            one_way = _echo_samples(echo_out, tags, expected, procs["echo"])
            return {sender: (one_way[tag], json.loads(outs[sender].read_text())["rtt_ns"])
                    for sender, tag in tags.items()}
        except (BenchError, OSError, ValueError, KeyError, subprocess.TimeoutExpired) as exc:
            error = exc if isinstance(exc, BenchError) else BenchError(f"{type(exc).__name__}: {exc}")
            return dict.fromkeys(senders, error)
        finally:
            for proc in procs.values():
                stop_process(proc)
            for fd in [*go.values(), *done.values()]:
                os.close(fd)
            for leftover in self.tmp.glob(f"{run.name}-*-go"):
                leftover.unlink()
            for leftover in self.tmp.glob(f"{run.name}-*-done"):
                leftover.unlink()

    def _start(self, role: str, kind: str, cfg: dict[str, Any], path: Path) -> subprocess.Popen[str]:
        cpus = self.cpus or []
        if kind == "rospy":
            return subprocess.Popen(["/usr/bin/python3", str(ROSPY_PEER), role, str(path)], env=self.env,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        keys = ("size", "warmup", "gap_s", "settle_s", "reps", "tag", "tags", "turns", "block")
        parameters = {key: cfg[key] for key in keys if key in cfg}
        parameters["out"] = cfg[f"{role}_out"]
        project = path.with_suffix(f".{role}.yaml")
        project.write_text(_project(role, cpus[1:2] if role == "echo" else cpus[0:1], parameters))
        return subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project)], env=self.env,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def _failed(procs: dict[str, subprocess.Popen[str]]) -> BenchError | None:
    for name, proc in procs.items():
        if proc.poll() is not None:
            return BenchError(f"{name} ended early: {_last_words(proc)}")
    return None


def _await_byte(fd: int, procs: dict[str, subprocess.Popen[str]], what: str, timeout: float) -> None:
    """One byte from a sender's "done" FIFO; BenchError when it ends or stays silent."""
    deadline = time.monotonic() + timeout
    while True:
        ready, _, _ = select.select([fd], [], [], 0.5)
        if ready:
            if os.read(fd, 1):
                return
            raise _failed(procs) or BenchError(f"waiting for {what}: the sender closed its FIFO")
        failed = _failed(procs)
        if failed is not None:
            raise failed
        if time.monotonic() > deadline:
            raise BenchError(f"waited {timeout:g} s for {what}")


def _open_fifo_writer(path: Path, procs: dict[str, subprocess.Popen[str]]) -> int:
    """The writing end of a FIFO whose reader (a sender) opens it any moment now."""
    deadline = time.monotonic() + 30
    while True:
        try:
            return os.open(path, os.O_WRONLY | os.O_NONBLOCK)
        except OSError as exc:
            if exc.errno != errno.ENXIO:
                raise
        failed = _failed(procs)
        if failed is not None:
            raise failed
        if time.monotonic() > deadline:
            raise BenchError(f"no sender opened {path.name} within 30 s")
        time.sleep(0.01)


def _echo_samples(path: Path, tags: dict[str, int], reps: int,
                  echo: subprocess.Popen[str]) -> dict[int, list[int]]:
    """The echo's one-way samples per tag, once it has written all of them down."""
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            written = json.loads(path.read_text())["one_way_ns"]
        except (OSError, ValueError, KeyError):
            written = {}
        if all(len(written.get(str(tag), ())) >= reps for tag in tags.values()):
            return {tag: list(written[str(tag)]) for tag in tags.values()}
        if echo.poll() is not None:
            raise BenchError(f"echo ended early: {_last_words(echo)}")
        time.sleep(0.05)
    raise BenchError("the echo did not write every sender's samples within 30 s")


def stop_process(proc: subprocess.Popen[str]) -> None:
    """SIGINT first (``hetros launch`` then shuts down in order), then kill."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _last_words(proc: subprocess.Popen[str]) -> str:
    err = proc.stderr.read() if proc.stderr is not None and proc.poll() is not None else ""
    return (err or "").strip()[-400:] or f"exit code {proc.returncode}"


class BenchError(Error):
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
    return [_last_words(p) for p in procs if p.wait() != 0]


def _project(role: str, cpus: list[int], parameters: dict[str, Any]) -> str:
    """A project with one hetros role alone on a ``kind: ros1`` target pinned to its CPU."""
    replies = [reply_topic(tag) for tag in parameters.get("tags", [parameters.get("tag", 0)])]
    out, into = (["/bench_send"], replies) if role == "ping" else (replies, ["/bench_send"])
    typed = ", ".join
    lines = [f"name: bench_ros1_{role}", "targets:", f"  {role}: {{kind: ros1, cpus: {cpus}}}", "nodes:",
             f"  {role}:", f"    run: hetros_bench._ros1_nodes:{role}", f"    target: {role}",
             "    required: true", f"    publish: {{{typed(f'{t}: std_msgs/msg/UInt8MultiArray' for t in out)}}}",
             f"    subscribe: {{{typed(f'{t}: std_msgs/msg/UInt8MultiArray' for t in into)}}}",
             f"    parameters: {json.dumps(parameters)}", "topics:"]
    lines += [f"  {topic}: {{reliability: reliable, history: keep_last, depth: 16}}"
              for topic in ["/bench_send", *replies]]
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
    parser.add_argument("--sizes", help="comma-separated subset of the sizes, as the tables label them or in "
                                        "bytes (e.g. 196kB,3146kB)")
    args = parser.parse_args(argv)
    sizes = SIZES
    if args.sizes:
        try:
            sizes = parse_sizes(args.sizes, SIZES)
        except ValueError as exc:
            parser.error(str(exc))
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
                turn = 1 if round_number % 2 == 0 else -1  # who goes first changes every round
                for size in sizes:
                    for receiver in ["rospy", "hetros"][::turn]:
                        senders = [sender for sender in ["rospy", "hetros"][::turn]
                                   if (pair_name(sender, receiver), size) not in failed]
                        if not senders:
                            continue
                        served = bench.run_receiver(receiver, senders, size, args.gap_ms / 1000.0, rounds,
                                                    args.settle_us / 1e6)
                        for sender, outcome in served.items():
                            key = (pair_name(sender, receiver), size)
                            if isinstance(outcome, BenchError):
                                failed[key] = str(outcome)
                                status = str(outcome).splitlines()[-1][:120] if str(outcome) else "failed"
                            else:
                                pooled = samples.setdefault(key, ([], []))
                                pooled[0].extend(outcome[0])
                                pooled[1].extend(outcome[1])
                                status = f"p50 {Stats.of(outcome[0]).p50:.1f} µs"
                            print(f"[bench] round {round_number}/{rounds} {key[0]:16} "
                                  f"{SIZE_LABELS.get(size, size):>8}: {status}", flush=True)
    finally:
        bench.close()
    for size in sizes:
        for sender, receiver in PAIRS:
            key = (pair_name(sender, receiver), size)
            if key in failed:
                results.append(Result(key[0], size, error=failed[key]))
            elif key in samples:
                results.append(Result(key[0], size, Stats.of(samples[key][0]), Stats.of(samples[key][1])))
    report = render(results, sizes, missing, STEADY_MALLOC if args.steady_malloc else "")
    print()
    print(report)
    (out / "ros1.md").write_text(provenance() + "\n\n" + report + "\n")
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
