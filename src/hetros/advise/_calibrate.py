"""What moving a message costs on this machine, measured and kept.

The advisor's model needs, per message size, the one-way latency of each transport a mapping can
give an edge (in one process; shared memory between processes, a subscriber's callback woken by
it) and the cost of a plain copy (what a gateway pays per message into and out of hardware).
``_measure`` measures them with hetros itself (the rows ``benchmarks/latency.py`` shows as
hetros-inproc, hetros-shm-cb and numpy-copy), once per machine, cached under
``$XDG_CACHE_HOME/hetros`` with the machine it describes: the library needs no benchmark package.

The ping-pongs' receivers are awake when a message comes (each spins on its reader for a while
after the last one). In a graph whose messages come a period apart they are asleep, and waking a
thread costs more than the transport itself on a virtual machine. So the calibration also launches
small graphs as users write them (a 50 Hz publisher and a callback in its process; then, each in a
launch of its own, the publisher and a callback in another process on the other core, and on the
publisher's core) and keeps, per kind of hop, what it takes beyond the benchmark's figure: the wake.
Two processes pinned to one core wake each other without waking another CPU, which here is a fifth
to a quarter cheaper (230-270 µs against 300-325 µs, 2026-11-29).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._errors import AdviseError
from .._files import load_json
from ._measure import BUSY_LIMIT, CHECK_SIZE, CHECK_TOLERANCE, busy_share, copy_check_us, hop_table
from ._profile import cpu_mhz, machine


def cache_path() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "hetros" / "calibration.json"


@dataclass
class Calibration:
    """Per transport (``inproc``, ``shm``, ``copy``): sizes (bytes) and one-way p50 and p99 (µs); per
    hop kind (``WAKES``: ``inproc``, ``shm``, ``shm_one_core``), what waking a sleeping subscriber adds (ms)."""

    machine: dict[str, object]
    table: dict[str, list[tuple[int, float, float]]]
    wake_ms: dict[str, float] = field(default_factory=dict)
    # how much of the calibrated wake a graph's hops pay: fitted on a profile's chains (not saved); a hop
    # within a process pinned to one core (its core awake, the subscriber next) pays ``warm_scale`` of it,
    # fitted on the chains of the profile's one-core launch
    wake_scale: float = 1.0
    warm_scale: float = 1.0

    def latency_ms(self, transport: str, size: int, *, p99: bool = False) -> float:
        """The one-way latency of ``size`` bytes over ``transport``, interpolated between the measured
        sizes (and extended along the last two beyond them), in ms."""
        rows = self.table.get(transport)
        if not rows:
            raise AdviseError(f"the calibration has no {transport!r} rows; calibrate again "
                              "(`hetros advise --calibrate`)")
        sizes = np.asarray([r[0] for r in rows], dtype=np.float64)
        values = np.asarray([r[2] if p99 else r[1] for r in rows], dtype=np.float64)
        if len(rows) > 1 and size > sizes[-1]:
            slope = (values[-1] - values[-2]) / (sizes[-1] - sizes[-2])
            return float(values[-1] + slope * (size - sizes[-1])) / 1000.0
        return float(np.interp(size, sizes, values)) / 1000.0

    def hop_ms(self, transport: str, size: int, wake: str | None = None, *, warm: bool = False) -> float:
        """One hop of ``size`` bytes to a sleeping subscriber: the transport and the wake (of the kind
        ``wake``, the transport's own by default; ``warm``: within a process pinned to one core)."""
        scale = self.warm_scale if warm else self.wake_scale
        return self.latency_ms(transport, size) + self.wake_ms.get(wake or transport, 0.0) * scale

    def stale(self) -> str:
        """Why this calibration no longer describes the machine ("" when it does): measured while other work
        kept the machine busy, or a copy now takes another time than it did (another CPU clock, another load)."""
        busy = float(str(self.machine.get("busy", 0.0)))
        if busy > BUSY_LIMIT:
            return f"it was measured while {busy:.0%} of the CPUs were busy"
        rows = [r for r in self.table.get("copy", []) if r[0] == CHECK_SIZE]
        if rows:
            now, then = copy_check_us(), rows[0][1]
            if not then / CHECK_TOLERANCE <= now <= then * CHECK_TOLERANCE:
                return f"a copy of {CHECK_SIZE // 1024} kB takes {now:.1f} µs now, {then:.1f} µs then"
        return ""

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({"machine": self.machine, "table": self.table, WAKE_KEY: self.wake_ms}, indent=1)
                        + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: Path) -> Calibration:
        raw = load_json(path, "calibration", error=AdviseError)
        try:
            table = {name: [(int(s), float(p50), float(p99)) for s, p50, p99 in rows]
                     for name, rows in raw["table"].items()}
            wake = {str(k): float(v) for k, v in raw.get(WAKE_KEY, {}).items()}
            return cls(dict(raw["machine"]), table, wake)
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise AdviseError(f"{path}: not a readable calibration ({exc!r}); calibrate again "
                              "(`hetros advise --calibrate`)") from None


def calibration(*, again: bool = False, path: Path | None = None, check: bool = True) -> tuple[Calibration, str]:
    """This machine's calibration, and where it came from: the cache when it describes this machine and still
    holds (``stale``, unless ``check`` is off), else one measured now (about half a minute), cached with the load
    it was measured under."""
    path = path or cache_path()
    why = "calibrated now"
    if path.exists() and not again:
        cached = Calibration.load(path)
        here = machine()
        if all(cached.machine.get(key) == here[key] for key in ("host", "cpu", "cpus", "hetros")) and \
                set(WAKES) <= set(cached.wake_ms):
            stale = cached.stale() if check else ""
            if not stale:
                return cached, f"cached calibration {path}"
            why = f"calibrated again: the cached one no longer holds ({stale})"
    measured = run_benchmark()
    measured.wake_ms = wakes(measured)
    measured.save(path)
    return measured, f"{why} (hop latencies and wakes measured on this machine), cached in {path}"


def run_benchmark() -> Calibration:
    """The hop table measured now (``_measure``: hetros's own ping-pongs, about half a minute), with the
    conditions it was measured under: the machine's busy share while it ran, and its CPU's clock."""
    busy = busy_share(0.5)
    table = hop_table()
    conditions = {"busy": round(max(busy, busy_share(0.5)), 3), "mhz": cpu_mhz()}
    return Calibration({**machine(), **conditions}, table)


# the wakes' key in the cached file: a calibration cached before each wake was measured alone (under
# "wake_ms") is measured again, as is one that lacks a kind of WAKES
WAKE_KEY = "wake_alone_ms"
# each kind of hop whose wake is measured: the listener's target in the launch (a: the publisher's
# process), and the listener's core (None: the other core)
WAKES: dict[str, tuple[str, int | None]] = {"inproc": ("a", 0), "shm": ("b", None), "shm_one_core": ("b", 0)}
WAKE_HZ = 50.0
WAKE_SAMPLES = 200
_WAKE_NODES = textwrap.dedent("""\
    import json
    import time

    from hetros import Node
    from hetros.interfaces.std_msgs.msg import Int64


    def ping(node: Node) -> None:
        pub = node.create_publisher(Int64, "/ping")
        for tick in node.rate(node.get_parameter("hz")):
            pub.publish(Int64(data=time.monotonic_ns()))
            if tick + 1 >= node.get_parameter("samples") + 20:
                return


    def listen(node: Node) -> None:
        seen = []
        out, wanted = node.get_parameter("out"), node.get_parameter("samples")

        def heard(message: Int64) -> None:
            seen.append(time.monotonic_ns() - message.data)
            if len(seen) == wanted + 10:  # the first ten are start-up
                with open(out, "w", encoding="utf-8") as handle:
                    json.dump(seen[10:], handle)

        node.create_subscription(Int64, "/ping", heard)
    """)


def wakes(measured: Calibration) -> dict[str, float]:
    """Per hop kind, a sporadic callback's one-way p50 beyond the benchmark's (ms, at least 0): a 50 Hz
    publisher heard by a callback in its own process, then (other launches) by one in another process on
    the other core and on its own. Each alone: heard by both at once, the callback in the publisher's
    process waited for the publish to the other (102 against 186 µs here), and a hop in a process came
    out dearer than chains pay."""
    found = {}
    for kind, (target, core) in WAKES.items():
        samples = _wake_samples(kind, target, core)
        p50_ms = float(np.percentile(np.asarray(samples, dtype=np.float64), 50)) / 1e6
        found[kind] = max(0.0, p50_ms - measured.latency_ms("inproc" if kind == "inproc" else "shm", 8))
    return found


def _wake_samples(kind: str, target: str, core: int | None) -> list[int]:
    """One launch: the publisher on CPU 0 (target a) and one listener on ``target`` (a, or b on ``core``;
    None: CPU 1, where there is one)."""
    with tempfile.TemporaryDirectory(prefix="hetros-wake-") as name:
        folder = Path(name)
        # a name of its own, run from its own folder: a nodes.py of the caller's must not stand in for it
        (folder / "hetros_wake_nodes.py").write_text(_WAKE_NODES, encoding="utf-8")
        cpus = f"[{core}]" if core is not None else "[0]" if len(os.sched_getaffinity(0)) < 2 else "[1]"
        common = f"hz: {WAKE_HZ}, samples: {WAKE_SAMPLES}"
        out = folder / f"{kind}.json"
        (folder / "project.yaml").write_text(textwrap.dedent(f"""\
            name: wake
            targets: {{a: {{kind: process, cpus: [0]}}, b: {{kind: process, cpus: {cpus}}}}}
            nodes:
              ping: {{run: hetros_wake_nodes:ping, target: a, parameters: {{{common}}},
                      publish: {{/ping: std_msgs/msg/Int64}}}}
              listen: {{run: hetros_wake_nodes:listen, target: {target}, subscribe: {{/ping: std_msgs/msg/Int64}},
                        parameters: {{{common}, out: {out}}}}}
            """), encoding="utf-8")
        seconds = (WAKE_SAMPLES + 30) / WAKE_HZ + 2
        done = subprocess.run([sys.executable, "-m", "hetros", "launch", str(folder / "project.yaml"), "--duration",
                               f"{seconds:g}"], capture_output=True, text=True, timeout=seconds + 120, check=False,
                              cwd=folder)
        try:
            samples: list[int] = json.loads(out.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            raise AdviseError(f"the wake-up calibration heard too little ({kind}); its launch said:\n"
                              f"{done.stderr[-2000:]}") from None
        return samples
