"""Latency, throughput and idle-CPU benchmark of hetros against the peers a Python user would pick.

    python benchmarks/latency.py [--quick] [--out DIR]      (or: hetros bench latency)

One run measures every system side by side, each ping and echo process pinned the same
way (ping on one CPU, echo on the other). It prints markdown tables, writes JSON lines
and a PNG plot, and reports every peer that could not run as missing, with the reason.
Timings are for comparison within one run: report ratios, not absolute numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from hetros.transport import cleanup_stale, new_session, remove_session_segments

from ._provenance import provenance

SIZES = [4, 3 * 1024, 12 * 1024, 48 * 1024, 192 * 1024, 768 * 1024, 3 * 1024 * 1024, 6 * 1024 * 1024]
SIZE_LABELS = {4: "4 B", 3072: "3 kB", 12288: "12 kB", 49152: "50 kB", 196608: "196 kB",
               786432: "786 kB", 3145728: "3146 kB", 6291456: "6 MiB"}
# -cb: the echo node is a subscription callback that publishes (what users write); the others
# take in a loop on both sides. -py: the same with HETROS_PURE_PYTHON=1 (no compiled hot path)
PURE_PYTHON = "-py"
# -rclpy-cb / -rospy-cb: the callback echo node written the rclpy or rospy way, run through hetros's shims;
# -rclpy-pp / -rospy-pp: the pinger too (both ends of the ping-pong as ROS users port them); -rospy-pp-cb: the
# rospy pinger's callback publishes the next ping (no reply handed from its callback thread to its main thread)
SYSTEMS = ["hetros-inproc", "hetros-shm", "hetros-shm-loan", "hetros-shm-cb", "hetros-shm-loan-cb",
           "hetros-rclpy-cb", "hetros-rospy-cb", "hetros-rclpy-pp", "hetros-rospy-pp", "hetros-rospy-pp-cb",
           "hetros-shm-py",
           "hetros-shm-cb-py", "iceoryx2", "cyclonedds",
           "zenoh", "dora-rs", "rospy", "mp-pipe", "numpy-copy"]
HETROS_SHM = ("hetros-shm", "hetros-shm-loan", "hetros-shm-cb", "hetros-shm-loan-cb", "hetros-rclpy-cb",
              "hetros-rospy-cb", "hetros-rclpy-pp", "hetros-rospy-pp", "hetros-rospy-pp-cb", "hetros-shm-py",
              "hetros-shm-cb-py")
HERE = Path(__file__).resolve().parent
LOOPBACK_CYCLONEDDS = textwrap.dedent("""\
    <CycloneDDS><Domain id="any">
      <General><Interfaces><NetworkInterface name="lo"/></Interfaces>
        <AllowMulticast>false</AllowMulticast></General>
      <Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>50</MaxAutoParticipantIndex>
        <Peers><Peer Address="127.0.0.1"/></Peers></Discovery>
    </Domain></CycloneDDS>""")


@dataclass
class Stats:
    mean: float
    std: float
    p50: float
    p99: float
    n: int

    @classmethod
    def of(cls, values_ns: list[int]) -> Stats:
        us = np.asarray(values_ns, dtype=np.float64) / 1000.0
        return cls(float(us.mean()), float(us.std()), float(np.percentile(us, 50)),
                   float(np.percentile(us, 99)), int(us.size))


@dataclass
class Result:
    system: str
    size: int
    one_way: Stats | None = None
    rtt: Stats | None = None
    error: str = ""
    # the samples behind the statistics, so that rounds can be pooled
    one_way_ns: list[int] = field(default_factory=list, repr=False)
    rtt_ns: list[int] = field(default_factory=list, repr=False)

    @classmethod
    def measured(cls, system: str, size: int, one_way_ns: list[int], rtt_ns: list[int] | None) -> Result:
        return cls(system, size, Stats.of(one_way_ns), Stats.of(rtt_ns) if rtt_ns else None,
                   one_way_ns=list(one_way_ns), rtt_ns=list(rtt_ns or []))


def pooled(results: list[Result]) -> Result:
    """One system and size measured in several rounds: their samples as one result (an error wins)."""
    failed = next((r for r in results if r.error), None)
    if failed is not None:
        return failed
    first = results[0]
    return Result.measured(first.system, first.size, [v for r in results for v in r.one_way_ns],
                           [v for r in results for v in r.rtt_ns] or None)


@dataclass
class Run:
    results: list[Result] = field(default_factory=list)
    missing: dict[str, str] = field(default_factory=dict)
    throughput: list[dict[str, Any]] = field(default_factory=list)
    cpu: list[dict[str, Any]] = field(default_factory=list)
    # the Python thread hand-over a rospy-style pinger pays (``_handover``), on the ping's core
    handover: dict[str, Any] = field(default_factory=dict)
    # each round's result per (system, size), for ratios that compare a round with itself
    rounds: dict[tuple[str, int], list[Result]] = field(default_factory=dict)


def round_ratio(run: Run, ours: str, theirs: str, size: int, statistic: str = "mean",
                less_us: float = 0.0) -> float | None:
    """Our round trip over theirs (its mean, or ``statistic``; ours less ``less_us``), round by round, the
    median of the rounds.

    Both rows of a round ran back to back, so they met the same speed phase of the machine;
    a phase that hit one round of ours but not theirs moves one ratio, not the median.
    """
    mine, other = run.rounds.get((ours, size), []), run.rounds.get((theirs, size), [])
    ratios: list[float] = sorted((getattr(a.rtt, statistic) - less_us) / getattr(b.rtt, statistic)
                                 for a, b in zip(mine, other, strict=False)
                                 if a.rtt is not None and b.rtt is not None and getattr(b.rtt, statistic) > 0)
    if not ratios:
        return None
    middle = len(ratios) // 2
    return ratios[middle] if len(ratios) % 2 else (ratios[middle - 1] + ratios[middle]) / 2


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def pipe_fds(cfg: dict[str, Any]) -> tuple[int, ...]:
    """Two pipes for the multiprocessing.Pipe peer, named in ``cfg`` for each role."""
    a_read, a_write = os.pipe()
    b_read, b_write = os.pipe()
    cfg["fds"] = {"ping": [b_read, a_write], "echo": [a_read, b_write]}
    return (a_read, a_write, b_read, b_write)


class Bench:
    def __init__(self, out: Path, quick: bool, cpus: list[int] | None) -> None:
        self.out = out
        self.quick = quick
        self.cpus = cpus
        self.tmp = Path(tempfile.mkdtemp(prefix="hetros-bench-"))
        self.env = dict(os.environ)
        self.env["CYCLONEDDS_URI"] = LOOPBACK_CYCLONEDDS
        self.env["DORA_ZENOH_MULTICAST"] = "off"
        self.env["DORA_NODE_SHM_POOL_SIZE"] = str(256 * 1024 * 1024)
        self.env["IOX2_LOG_LEVEL"] = "Error"
        self.env.setdefault("RUST_LOG", "error")
        self.rosmaster: subprocess.Popen[bytes] | None = None
        self.sessions: list[str] = []

    def reps_for(self, size: int) -> tuple[int, int]:
        if self.quick:
            return (10, 100) if size <= 196608 else (5, 20)
        return (50, 1000) if size <= 196608 else (10, 200)

    def config(self, system: str, size: int) -> tuple[dict[str, Any], Path]:
        warmup, reps = self.reps_for(size)
        tag = f"{system}-{size}"
        session = new_session()
        self.sessions.append(session)
        cfg: dict[str, Any] = {
            "size": size, "warmup": warmup, "reps": reps, "cpus": self.cpus,
            "session": session,
            "ping_out": str(self.tmp / f"{tag}-ping.json"), "echo_out": str(self.tmp / f"{tag}-echo.json"),
            "inproc_out": str(self.tmp / f"{tag}-inproc.json"), "port": free_port(),
        }
        path = self.tmp / f"{tag}.json"
        return cfg, path

    # -- systems ---------------------------------------------------------------------------

    def spawn_pair(self, receiver: list[str], sender: list[str], pass_fds: tuple[int, ...], delay: float = 0.0,
                   env: dict[str, str] | None = None) -> tuple[subprocess.Popen[str], subprocess.Popen[str]]:
        """Start the receiving side, then the sending side; the pipes passed to them close here."""
        env = self.env if env is None else env
        first = subprocess.Popen(receiver, env=env, stderr=subprocess.PIPE, text=True, pass_fds=pass_fds)
        if delay:
            time.sleep(delay)
        second = subprocess.Popen(sender, env=env, stderr=subprocess.PIPE, text=True, pass_fds=pass_fds)
        for fd in pass_fds:
            os.close(fd)
        return first, second

    def run_pair(self, system: str, size: int) -> Result:
        cfg, path = self.config(system, size)
        role_system, env = self.variant(system)
        roles = [sys.executable, "-m", "hetros_bench._roles", role_system]
        pass_fds = pipe_fds(cfg) if system == "mp-pipe" else ()
        path.write_text(json.dumps(cfg))
        timeout = 600
        if system == "hetros-inproc":
            proc = subprocess.run([*roles, "inproc", str(path)], env=self.env, capture_output=True, text=True,
                                  timeout=timeout, check=False)
            if proc.returncode != 0:
                return Result(system, size, error=proc.stderr.strip()[-400:])
            data = json.loads(Path(cfg["inproc_out"]).read_text())
            return Result.measured(system, size, data["one_way_ns"], data["rtt_ns"])
        if system == "rospy":
            cmd = ["/usr/bin/python3", str(HERE / "_rospy_peer.py")]
            echo, ping = self.spawn_pair([*cmd, "echo", str(path)], [*cmd, "ping", str(path)], (), delay=0.5)
        else:
            echo, ping = self.spawn_pair([*roles, "echo", str(path)], [*roles, "ping", str(path)], pass_fds, env=env)
        try:
            _, ping_err = ping.communicate(timeout=timeout)
            _, echo_err = echo.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            ping.kill()
            echo.kill()
            return Result(system, size, error="timed out")
        if ping.returncode != 0 or echo.returncode != 0:
            return Result(system, size, error=(ping_err + echo_err).strip()[-400:])
        rtt = json.loads(Path(cfg["ping_out"]).read_text())["rtt_ns"]
        one_way = json.loads(Path(cfg["echo_out"]).read_text())["one_way_ns"]
        return Result.measured(system, size, one_way, rtt)

    def run_dora(self, size: int) -> Result:
        cfg, path = self.config("dora-rs", size)
        path.write_text(json.dumps(cfg))
        node = HERE / "_dora_node.py"
        flow = self.tmp / f"dora-{size}.yml"
        flow.write_text(textwrap.dedent(f"""\
            nodes:
              - id: ping
                path: {node}
                inputs: {{reply: echo/out}}
                outputs: [out]
                env: {{BENCH_ROLE: ping, BENCH_CONFIG: "{path}"}}
              - id: echo
                path: {node}
                inputs: {{msg: ping/out}}
                outputs: [out]
                env: {{BENCH_ROLE: echo, BENCH_CONFIG: "{path}"}}
            """))
        dora = shutil.which("dora", path=str(Path(sys.executable).parent)) or shutil.which("dora")
        if dora is None:
            return Result("dora-rs", size, error="the dora CLI is not installed (pip install dora-rs-cli)")
        env = dict(self.env)
        env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
        proc = subprocess.run([dora, "run", str(flow)], env=env, capture_output=True, text=True, timeout=900,
                              check=False, cwd=self.tmp)
        try:
            rtt = json.loads(Path(cfg["ping_out"]).read_text())["rtt_ns"]
            one_way = json.loads(Path(cfg["echo_out"]).read_text())["one_way_ns"]
        except (OSError, KeyError, json.JSONDecodeError):
            return Result("dora-rs", size, error=(proc.stderr or proc.stdout).strip()[-400:] or "no results")
        return Result.measured("dora-rs", size, one_way, rtt)

    def run_numpy_copy(self, size: int) -> Result:
        from hetros.advise import copy_times

        return Result.measured("numpy-copy", size, copy_times(size, *self.reps_for(size)), None)

    def start_rosmaster(self) -> str:
        if not Path("/usr/bin/rosmaster").exists():
            raise FileNotFoundError("Debian's rosmaster is not installed (apt-get install ros-core python3-rospy)")
        port = free_port()
        uri = f"http://127.0.0.1:{port}"
        ros_home = self.tmp / "ros"
        ros_home.mkdir(exist_ok=True)
        self.env.update({"ROS_MASTER_URI": uri, "ROS_HOSTNAME": "127.0.0.1", "ROS_HOME": str(ros_home),
                         "ROS_LOG_DIR": str(ros_home)})
        self.rosmaster = subprocess.Popen(["/usr/bin/rosmaster", "--core", "-p", str(port)], env=self.env,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        import xmlrpc.client

        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            try:
                xmlrpc.client.ServerProxy(uri).getSystemState("/bench")
                return uri
            except OSError:
                time.sleep(0.2)
        raise TimeoutError("rosmaster did not come up on 127.0.0.1")

    def available(self, system: str) -> str:
        """Empty when ``system`` can run here, else why not."""
        probes = {"cyclonedds": "cyclonedds", "zenoh": "zenoh", "dora-rs": "dora", "iceoryx2": "iceoryx2"}
        if system in probes:
            check = subprocess.run([sys.executable, "-c", f"import {probes[system]}"], capture_output=True,
                                   text=True, check=False, env=self.env)
            if check.returncode != 0:
                return f"cannot import {probes[system]} (pip install -e '.[bench]')"
        if system == "rospy":
            check = subprocess.run(["/usr/bin/python3", "-c", "import rospy, std_msgs.msg"], capture_output=True,
                                   text=True, check=False)
            if check.returncode != 0:
                return "Debian's rospy is missing (apt-get install ros-core python3-rospy python3-std-msgs)"
            try:
                self.start_rosmaster()
            except (OSError, TimeoutError) as exc:
                return str(exc)
        return ""

    def run_system(self, system: str, size: int) -> Result:
        if system == "numpy-copy":
            return self.run_numpy_copy(size)
        if system == "dora-rs":
            return self.run_dora(size)
        return self.run_pair(system, size)

    # -- throughput and idle CPU -------------------------------------------------------------

    def variant(self, system: str) -> tuple[str, dict[str, str]]:
        """The system the roles run and their environment: a ``-py`` row is its base row in pure Python."""
        if system.endswith(PURE_PYTHON):
            return system.removesuffix(PURE_PYTHON), {**self.env, "HETROS_PURE_PYTHON": "1"}
        return system, self.env

    def throughput(self, system: str, size: int, seconds: float) -> dict[str, Any]:
        cfg, path = self.config(system, size)
        cfg["seconds"] = seconds
        pass_fds = pipe_fds(cfg) if system == "mp-pipe" else ()
        path.write_text(json.dumps(cfg))
        role_system, env = self.variant(system)
        cmd = [sys.executable, "-m", "hetros_bench._throughput", role_system]
        sub, pub = self.spawn_pair([*cmd, "sub", str(path)], [*cmd, "pub", str(path)], pass_fds, env=env)
        _, pub_err = pub.communicate(timeout=120)
        _, sub_err = sub.communicate(timeout=60)
        if pub.returncode or sub.returncode:
            return {"system": system, "size": size, "error": (pub_err + sub_err).strip()[-300:]}
        data = json.loads(Path(cfg["echo_out"]).read_text())
        return {"system": system, "size": size, **data}

    def idle_cpu(self, seconds: float) -> list[dict[str, Any]]:
        out = []
        cases = [("node with a 100 Hz timer", "cpu", 0.01), ("idle node (subscription, no traffic)", "cpu", 0.0),
                 ("timer node publishing + take-loop subscriber, 100 Hz", "cpu-receiving", 100.0),
                 ("timer node publishing + take-loop subscriber, 1 kHz", "cpu-receiving", 1000.0)]
        for label, mode, value in cases:
            proc = subprocess.run([sys.executable, "-m", "hetros_bench._throughput", mode, str(value),
                                   str(seconds)], capture_output=True, text=True, env=self.env, check=False,
                                  timeout=seconds + 60)
            if proc.returncode:
                out.append({"what": label, "error": proc.stderr.strip()[-300:]})
                continue
            data = json.loads(proc.stdout.strip().splitlines()[-1])
            out.append({"what": label, **data})
        return out

    def handover(self) -> dict[str, Any]:
        """The floor the rospy structure adds to a round trip (``_handover``), on the ping's core."""
        cpu = "-" if self.cpus is None else str(self.cpus[0])
        proc = subprocess.run([sys.executable, "-m", "hetros_bench._handover", cpu], capture_output=True, text=True,
                              env=self.env, check=False, timeout=300)
        if proc.returncode:
            return {"error": proc.stderr.strip()[-300:]}
        measured: dict[str, Any] = json.loads(proc.stdout.strip().splitlines()[-1])
        return measured

    def close(self) -> None:
        if self.rosmaster is not None:
            self.rosmaster.terminate()
            self.rosmaster.wait(10)
        shutil.rmtree(self.tmp, ignore_errors=True)
        for session in self.sessions:
            remove_session_segments(session)
        cleanup_stale()


# -- report ------------------------------------------------------------------------------------

def parse_sizes(text: str, known: list[int]) -> list[int]:
    """``--sizes`` as the user wrote it (bytes or the tables' labels, comma-separated), in ``known``'s order.

    Raises ValueError naming the size that is not one of ``known``.
    """
    by_name = {str(size): size for size in known} | {SIZE_LABELS[size].replace(" ", ""): size
                                                      for size in known if size in SIZE_LABELS}
    chosen = set()
    for word in (w.strip().replace(" ", "") for w in text.split(",")):
        if word not in by_name:
            choices = ", ".join(SIZE_LABELS.get(size, str(size)).replace(" ", "") for size in known)
            raise ValueError(f"--sizes: each size must be one of {choices} (or its bytes), not {word!r}")
        chosen.add(by_name[word])
    return [size for size in known if size in chosen]


def fmt(value: float) -> str:
    return f"{value:.1f}" if value < 1000 else f"{value:,.0f}"


def _table(lines: list[str], title: str, columns: list[str], sizes: list[int],
           cell: Callable[[int, str], str]) -> None:
    lines += ["", f"### {title}", "", "| size | " + " | ".join(columns) + " |", "|---|" + "---|" * len(columns)]
    for size in sizes:
        lines.append(f"| {SIZE_LABELS.get(size, size)} | " + " | ".join(cell(size, c) for c in columns) + " |")


def render(run: Run, systems: list[str], sizes: list[int]) -> str:
    by = {(r.system, r.size): r for r in run.results}
    shown = [s for s in systems if s not in run.missing]

    def stat(metric: str, text: Callable[[Stats], str]) -> Callable[[int, str], str]:
        def cell(size: int, system: str) -> str:
            r = by.get((system, size))
            value = None if r is None else getattr(r, metric)
            return "err" if r is not None and r.error else ("-" if value is None else text(value))
        return cell

    lines: list[str] = []
    _table(lines, "One-way latency, p50 µs (p99)", shown, sizes,
           stat("one_way", lambda s: f"{fmt(s.p50)} ({fmt(s.p99)})"))
    _table(lines, "One-way latency, mean ± std µs", shown, sizes,
           stat("one_way", lambda s: f"{fmt(s.mean)} ± {fmt(s.std)}"))
    _table(lines, "Round trip with a copy in the echo node (ReconROS Table 3), mean ± std µs",
           [s for s in shown if s != "numpy-copy"], sizes, stat("rtt", lambda s: f"{fmt(s.mean)} ± {fmt(s.std)}"))
    def ratio(ours: str, metric: str, field: str, invert: bool = False) -> Callable[[int, str], str]:
        def cell(size: int, other: str) -> str:
            mine, theirs = by.get((ours, size)), by.get((other, size))
            a = None if mine is None else getattr(mine, metric)
            b = None if theirs is None else getattr(theirs, metric)
            if a is None or b is None:
                return "-"
            value = getattr(a, field) / getattr(b, field) if invert else getattr(b, field) / getattr(a, field)
            return f"{value:.2f}x" if invert else f"{value:.1f}x"
        return cell

    def shim_cost(size: int, shim: str) -> str:
        mine, native = by.get((shim, size)), by.get(("hetros-shm-cb", size))
        if mine is None or native is None or mine.one_way is None or native.one_way is None:
            return "-"
        return f"{mine.one_way.p50 / native.one_way.p50:.2f}x"

    shims: list[str] = [s for s in ("hetros-rclpy-cb", "hetros-rospy-cb") if s in shown]
    if shims and "hetros-shm-cb" in shown:
        _table(lines, "Cost of the rclpy and rospy shims: p50 one-way of the unchanged ROS-style echo node / "
                      "hetros-shm-cb p50", shims, sizes, shim_cost)
    both: list[str] = [s for s in ("hetros-rclpy-pp", "hetros-rospy-pp", "hetros-rospy-pp-cb") if s in shown]

    def both_ends(less_us: float = 0.0) -> Callable[[int, str], str]:
        """A ported ping-pong's p50 round trip, less ``less_us``, over hetros-shm-cb's, round by round."""
        def cell(size: int, ported: str) -> str:
            value = round_ratio(run, ported, "hetros-shm-cb", size, "p50", less_us)
            return "-" if value is None else f"{value:.2f}x"
        return cell

    floor = run.handover.get("floor_us")
    if both and "hetros-shm-cb" in shown:
        _table(lines, "Both ends written the ROS way: p50 round trip of the unchanged rclpy/rospy ping-pong / "
                      "hetros-shm-cb p50 (the same pair in hetros's API; with rounds, the median of the rounds' "
                      "ratios)", both, sizes, both_ends())
        if floor is not None and "hetros-rospy-pp" in both:
            lines += ["", f"hetros-rospy-pp's pinger waits in its main thread for what its callback thread "
                          f"receives: each round trip passes the reply from one thread to the other and wakes a "
                          f"sleeping thread (hetros-rospy-pp-cb's pinger publishes from its callback: it passes "
                          f"nothing). Without any transport, on the ping's core in this run, that hand-over took "
                          f"{run.handover['event_wait_us']:.1f} µs (p50) against "
                          f"{run.handover.get('one_thread_us', 0.0):.1f} µs for the same token within one "
                          f"thread: a floor of {floor:.1f} µs (`hetros_bench._handover`)."]
            _table(lines, "The rospy ping-pong less that floor / hetros-shm-cb p50", ["hetros-rospy-pp"], sizes,
                   both_ends(floor))
    peers = [s for s in shown if not s.startswith("hetros") and s != "numpy-copy"]
    for ours in ("hetros-shm-cb", "hetros-shm-loan-cb", "hetros-shm-loan", "hetros-inproc"):
        if ours in shown:
            _table(lines, f"Speed-up of {ours} (p50 one-way) over each peer: peer p50 / {ours} p50",
                   peers, sizes, ratio(ours, "one_way", "p50"))
    if "iceoryx2" in shown:
        ours_shm: list[str] = [s for s in HETROS_SHM if s in shown]

        def overhead(size: int, ours: str) -> str:
            value = round_ratio(run, ours, "iceoryx2", size)
            return "-" if value is None else f"{value:.2f}x"

        _table(lines, "Framework overhead: hetros round trip / iceoryx2 round trip (mean, same wait strategy; "
                      "with rounds, the median of the rounds' ratios)", ours_shm, sizes, overhead)
    if run.throughput:
        lines += ["", "### Throughput, one publisher, one subscriber in another process", ""]
        lines.append("| system | size | messages/s | MiB/s |")
        lines.append("|---|---|---|---|")
        for t in run.throughput:
            if "error" in t:
                lines.append(f"| {t['system']} | {t['size']} B | error | {t['error'][:60]} |")
            else:
                lines.append(f"| {t['system']} | {t['size']} B | {t['rate']:,.0f} | "
                             f"{t['rate'] * t['size'] / 2**20:,.1f} |")
    if run.cpu:
        lines += ["", "### CPU share of one core", ""]
        lines.append("| what | CPU % |")
        lines.append("|---|---|")
        for c in run.cpu:
            lines.append(f"| {c['what']} | {c.get('cpu_percent', float('nan')):.2f} |")
    if run.missing:
        lines += ["", "### Missing peers", ""]
        for system, why in run.missing.items():
            lines.append(f"- {system}: {why}")
    errors = [r for r in run.results if r.error]
    if errors:
        lines += ["", "### Errors", ""]
        for r in errors:
            lines.append(f"- {r.system} at {SIZE_LABELS.get(r.size, r.size)}: {r.error.splitlines()[-1][:200]}")
    return "\n".join(lines)


def plot(run: Run, systems: list[str], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(13, 5))
    for system in systems:
        points = [(r.size, r.one_way.p50) for r in run.results
                  if r.system == system and r.one_way is not None and not r.error]
        rtts = [(r.size, r.rtt.mean) for r in run.results if r.system == system and r.rtt is not None]
        style = "-o" if system.startswith("hetros") else "--."
        if points:
            axes[0].plot(*zip(*points, strict=True), style, label=system)
        if rtts:
            axes[1].plot(*zip(*rtts, strict=True), style, label=system)
    for ax, title in zip(axes, ("one-way latency, p50", "round trip with copy, mean"), strict=True):
        log_axes(ax, title, "µs")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def log_axes(ax: Any, title: str, unit: str) -> None:
    """Payload size against time, both logarithmic: how every latency plot here looks."""
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("payload bytes")
    ax.set_ylabel(unit)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)


# sizes from which a loan must be at least as fast as a plain publish: its arrays are not copied. Where both
# cost the same copy (one way, a producer that writes its data) they differ by this machine's noise, a few
# per cent either way: a loan more than 10 % slower is the regression (it was 3-6x when it happened)
LOAN_PAYS_FROM = 196 * 1024
LOAN_NOISE = 1.10


def loan_regressions(results: list[Result]) -> list[str]:
    """Each size (from ``LOAN_PAYS_FROM``) at which the loaned publish was slower than the plain one in this run
    (beyond ``LOAN_NOISE``), one line each: the zero-copy path users of large messages are told to take must
    never lose to a copy."""
    p50 = {(r.system, r.size): r.one_way.p50 for r in results if r.one_way is not None}
    return [f"hetros-shm-loan is slower than hetros-shm at {SIZE_LABELS.get(size, size)}: p50 {loaned:.1f} µs "
            f"against {p50[('hetros-shm', size)]:.1f} µs"
            for (system, size), loaned in sorted(p50.items())
            if system == "hetros-shm-loan" and size >= LOAN_PAYS_FROM and ("hetros-shm", size) in p50
            and loaned > LOAN_NOISE * p50[("hetros-shm", size)]]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="fewer sizes and repetitions (about a minute on 2 cores)")
    parser.add_argument("--out", default="out/bench", help="folder for latency.jsonl, latency.md, latency.png")
    parser.add_argument("--systems", help="comma-separated subset of: " + ", ".join(SYSTEMS))
    parser.add_argument("--no-pin", action="store_true", help="do not pin ping and echo to separate CPUs")
    parser.add_argument("--sizes", help="comma-separated subset of the sizes, as the tables label them or in "
                                        "bytes (e.g. 4B,196kB)")
    parser.add_argument("--rounds", type=int, default=1,
                        help="go round every system and size this many times and pool each one's samples "
                             "(this machine's speed drifts in phases; rounds spread the drift over all rows)")
    args = parser.parse_args(argv)
    if args.rounds < 1:
        parser.error(f"--rounds must be at least 1, not {args.rounds}")
    systems = args.systems.split(",") if args.systems else list(SYSTEMS)
    sizes = [4, 3072, 196608, 3145728] if args.quick else SIZES
    if args.sizes:
        try:
            sizes = parse_sizes(args.sizes, SIZES)
        except ValueError as exc:
            parser.error(str(exc))
    cpus = None if args.no_pin or (os.cpu_count() or 1) < 2 else [0, 1]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    bench = Bench(out, args.quick, cpus)
    run = Run()
    try:
        for system in systems:
            why = bench.available(system)
            if why:
                run.missing[system] = why
                print(f"[bench] {system}: missing: {why}", flush=True)
        rounds = run.rounds
        for number in range(1, args.rounds + 1):
            # every system at one size back to back: this machine switches between speed phases
            # (measured: 3 MiB across processes took 0.14 ms, then 1.4 ms for every system, raw
            # iceoryx2 too, for minutes), so the rows a ratio compares must meet the same phase
            for size in sizes:
                for system in (s for s in systems if s not in run.missing):
                    result = bench.run_system(system, size)
                    rounds.setdefault((system, size), []).append(result)
                    status = result.error.splitlines()[-1][:120] if result.error else (
                        f"p50 {result.one_way.p50:.1f} µs" if result.one_way else "")
                    where = f" (round {number}/{args.rounds})" if args.rounds > 1 else ""
                    print(f"[bench] {system:16} {SIZE_LABELS.get(size, size):>8}: {status}{where}", flush=True)
        run.results = [pooled(results) for results in rounds.values()]
        tp_seconds = 1.0 if args.quick else 3.0
        for system in ("hetros-shm", "hetros-shm-loan", "hetros-shm-py", "iceoryx2", "mp-pipe"):
            if system in systems:
                for size in (64, 1024 * 1024):
                    run.throughput.append(bench.throughput(system, size, tp_seconds))
        run.cpu = bench.idle_cpu(3.0 if args.quick else 10.0)
        if "hetros-rospy-pp" in systems and "hetros-rospy-pp" not in run.missing:
            run.handover = bench.handover()
    finally:
        bench.close()
    report = render(run, systems, sizes)
    print()
    print(report)
    (out / "latency.md").write_text(provenance() + "\n\n" + report + "\n")
    with (out / "latency.jsonl").open("w") as handle:
        for r in run.results:
            handle.write(json.dumps({"system": r.system, "size": r.size, "error": r.error,
                                     "one_way_us": r.one_way.__dict__ if r.one_way else None,
                                     "rtt_us": r.rtt.__dict__ if r.rtt else None}) + "\n")
        for t in run.throughput:
            handle.write(json.dumps({"throughput": t}) + "\n")
        for c in run.cpu:
            handle.write(json.dumps({"cpu": c}) + "\n")
        if run.handover:
            handle.write(json.dumps({"handover": run.handover}) + "\n")
        for system, why in run.missing.items():
            handle.write(json.dumps({"missing": system, "why": why}) + "\n")
    plot(run, [s for s in systems if s not in run.missing], out / "latency.png")
    print(f"\nwrote {out / 'latency.md'}, {out / 'latency.jsonl'}, {out / 'latency.png'}")
    regressions = loan_regressions(run.results)
    for line in regressions:  # loud: the run fails, so that a regression of the zero-copy path cannot pass unseen
        print(f"REGRESSION: {line}", file=sys.stderr)
    return 1 if regressions else 0


if __name__ == "__main__":
    sys.exit(main())
