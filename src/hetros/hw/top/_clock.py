"""The clock an fpga target's figures use: its ``clock_mhz``, unless place and route showed that the design
cannot reach it.

``hetros hw bitstream`` records the Fmax nextpnr achieved for a target's whole design, keyed by what the
design is made of (:func:`design_key`, the key of the simulator cache too). The launch's simulated-time
lines and ``hetros hw report`` then use the lower of ``clock_mhz`` and that Fmax, and say which: a
speed-up computed at a clock the design misses is not one.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ...plan import Plan
    from ._build import HardwareTopic


@dataclass(frozen=True)
class TargetClock:
    """The clock figures use, and in words where it came from (printed beside every figure)."""

    mhz: float
    source: str


def design_key(plan: Plan, target: str, topics: list[HardwareTopic], sources: list[Path]) -> str:
    """What the target's hardware is made of, as sources: its nodes' ``hw:`` and parameters, its topics,
    the target's stream width, Amaranth's version, and the text of hetros's hardware modules, of every
    Python file of the project folder, of each hardware node's module and of its Verilog sources."""
    import amaranth

    spec = plan.targets[target]
    parts = [amaranth.__version__, str(spec.data_width), repr(topics)]
    hardware = Path(__file__).parents[1]  # every module of hetros.hw, and the simulator's C++ harness
    files = sorted(hardware.rglob("*.py")) + sorted(hardware.rglob("*.cpp")) + sorted(Path(plan.root).rglob("*.py")) \
        + sources
    for name, node in sorted(plan.nodes.items()):
        if node.target == target and plan.in_hardware(name):
            parts.append(f"{name}={node.hw}:{json.dumps(node.parameters, sort_keys=True, default=str)}:{node.memory}")
            module = sys.modules.get(node.hw.partition(":")[0])
            source = getattr(module, "__file__", None)
            if source:
                files.append(Path(source))
    digest = hashlib.sha256("\0".join(parts).encode())
    for path in files:
        if ".venv" not in path.parts and path.is_file():
            digest.update(str(path).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def target_key(plan: Plan, target: str) -> str:
    """:func:`design_key` of the whole target, without building its nodes (their Verilog files are read
    from the plan, as ``verilog_sources`` would list them)."""
    from ..designs._verilog_node import is_verilog
    from ._build import hardware_topics

    sources = sorted({(Path(plan.root) / node.hw.partition(":")[0]).resolve() for name, node in plan.nodes.items()
                      if node.target == target and node.hw and plan.in_hardware(name) and is_verilog(node.hw)})
    return design_key(plan, target, hardware_topics(plan, target), sources)


def _fmax_file(key: str) -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "hetros" / "fmax" / f"{key}.json"


def record_fmax(key: str, fmax_mhz: float, device: str, critical_path: str) -> None:
    """Remember what place and route achieved for the design ``key`` (``hetros hw bitstream``)."""
    path = _fmax_file(key)
    path.parent.mkdir(parents=True, exist_ok=True)
    record = {"fmax_mhz": fmax_mhz, "device": device, "critical_path": critical_path,
              "measured": time.strftime("%Y-%m-%d %H:%M", time.localtime())}
    temporary = path.with_suffix(f".{os.getpid()}.tmp")
    temporary.write_text(json.dumps(record), encoding="utf-8")
    temporary.replace(path)


def target_clock(plan: Plan, target: str, key: str | None = None) -> TargetClock:
    """The lower of the target's ``clock_mhz`` and the Fmax last measured for this very design."""
    wanted = plan.targets[target].clock_mhz
    try:
        record = json.loads(_fmax_file(key or target_key(plan, target)).read_text(encoding="utf-8"))
        fmax = float(record["fmax_mhz"])
        measured, device = str(record.get("measured", "")), str(record.get("device", "ECP5"))
    except (OSError, ValueError, KeyError, TypeError):
        return TargetClock(wanted, "clock_mhz; no `hetros hw bitstream` of this design yet")
    if not fmax > 0:
        return TargetClock(wanted, "clock_mhz; the recorded Fmax is not a clock")
    if fmax < wanted:
        return TargetClock(fmax, f"the Fmax place and route achieved on {device} ({measured}), below clock_mhz "
                                 f"{wanted:g}")
    return TargetClock(wanted, f"clock_mhz, which place and route met on {device} ({measured}: {fmax:.1f} MHz)")
