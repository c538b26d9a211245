"""What moving a message costs on this machine, measured by the latency benchmark and kept.

The advisor's model needs, per message size, the one-way latency of each transport a mapping can
give an edge (in one process; shared memory between processes, a subscriber's callback woken by
it) and the cost of a plain copy (what a gateway pays per message into and out of hardware).
Those are rows of ``benchmarks/latency.py``; its shortest variant (``--quick``, three systems) runs
once per machine and is cached under ``$XDG_CACHE_HOME/hetros`` with the machine it describes.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._errors import AdviseError
from ._profile import machine

SYSTEMS = {"inproc": "hetros-inproc", "shm": "hetros-shm-cb", "copy": "numpy-copy"}


def cache_path() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "hetros" / "calibration.json"


@dataclass
class Calibration:
    """Per transport (``inproc``, ``shm``, ``copy``): sizes (bytes) and one-way p50 and p99 (µs)."""

    machine: dict[str, object]
    table: dict[str, list[tuple[int, float, float]]]

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

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({"machine": self.machine, "table": self.table}, indent=1) + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: Path) -> Calibration:
        try:
            raw = json.loads(path.read_text(encoding="utf-8"))
            table = {name: [(int(s), float(p50), float(p99)) for s, p50, p99 in rows]
                     for name, rows in raw["table"].items()}
            return cls(dict(raw["machine"]), table)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise AdviseError(f"{path}: not a readable calibration ({exc!r}); calibrate again "
                              "(`hetros advise --calibrate`)") from None

    @classmethod
    def from_benchmark(cls, jsonl: Path) -> Calibration:
        """The rows the latency benchmark wrote (``latency.jsonl``)."""
        wanted = {system: name for name, system in SYSTEMS.items()}
        table: dict[str, list[tuple[int, float, float]]] = {}
        errors = []
        for line in jsonl.read_text(encoding="utf-8").splitlines():
            row = json.loads(line)
            name = wanted.get(row.get("system", ""))
            if name is None:
                continue
            if row.get("error") or not row.get("one_way_us"):
                errors.append(f"{row['system']} at {row['size']} B: {row.get('error') or 'no samples'}")
                continue
            table.setdefault(name, []).append((int(row["size"]), float(row["one_way_us"]["p50"]),
                                               float(row["one_way_us"]["p99"])))
        missing = sorted(set(SYSTEMS) - set(table))
        if missing:
            raise AdviseError(f"the latency benchmark measured no {', '.join(missing)} ({'; '.join(errors) or jsonl})")
        return cls(machine(), {name: sorted(rows) for name, rows in table.items()})


def calibration(*, again: bool = False, path: Path | None = None) -> tuple[Calibration, str]:
    """This machine's calibration, and where it came from: the cache when it describes this machine,
    else a run of the latency benchmark's shortest variant (about a minute), cached."""
    path = path or cache_path()
    if path.exists() and not again:
        cached = Calibration.load(path)
        here = machine()
        if all(cached.machine.get(key) == here[key] for key in ("host", "cpu", "cpus", "hetros")):
            return cached, f"cached calibration {path}"
    measured = run_benchmark()
    measured.save(path)
    return measured, f"calibrated now (benchmarks/latency.py --quick), cached in {path}"


def run_benchmark() -> Calibration:
    if importlib.util.find_spec("hetros_bench") is None:  # installed by `make install-bench`, the test set-up
        raise AdviseError("calibrating needs the benchmarks package (hetros_bench): `make install-bench`, or "
                          "`pip install -e benchmarks` in a checkout; or pass a calibration file (--calibration)")
    with tempfile.TemporaryDirectory(prefix="hetros-calibrate-") as folder:
        script = "import sys; from hetros_bench.latency import main; sys.exit(main(sys.argv[1:]))"
        command = [sys.executable, "-c", script, "--quick", "--systems", ",".join(SYSTEMS.values()), "--out", folder]
        done = subprocess.run(command, capture_output=True, text=True, timeout=900, check=False)
        jsonl = Path(folder) / "latency.jsonl"
        if not jsonl.exists():
            raise AdviseError(f"the latency benchmark failed (exit {done.returncode}):\n{done.stderr[-2000:]}")
        return Calibration.from_benchmark(jsonl)
