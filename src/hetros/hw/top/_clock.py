"""The clock an fpga target's figures use: its ``clock_mhz``, unless place and route showed that the design
cannot reach it.

``hetros hw bitstream`` records the Fmax nextpnr achieved for a target's whole design, keyed by what the
design is made of (:func:`design_key`, the key of the simulator cache too). The launch's simulated-time
lines and ``hetros hw report`` then use the lower of ``clock_mhz`` and that Fmax, and say which: a
speed-up computed at a clock the design misses is not one.
"""

from __future__ import annotations

import hashlib
import importlib.util
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
    # every module of hetros.hw that shapes a design or its simulator (its C++ harness too); not the flow that
    # places it nor this record of what placing gave, so that improving those keeps the figures
    hardware = Path(__file__).parents[1]
    shaping = [path for path in sorted(hardware.rglob("*.py")) + sorted(hardware.rglob("*.cpp"))
               if "flow" not in path.relative_to(hardware).parts and path.resolve() != Path(__file__).resolve()]
    files = shaping + sorted(Path(plan.root).rglob("*.py")) + sources
    for name, node in sorted(plan.nodes.items()):
        if node.target == target and plan.in_hardware(name):
            parts.append(f"{name}={node.hw}:{json.dumps(node.parameters, sort_keys=True, default=str)}:{node.memory}")
            source = _module_file(node.hw.partition(":")[0])
            if source:
                files.append(Path(source))
    digest = hashlib.sha256("\0".join(parts).encode())
    for path in files:
        if ".venv" not in path.parts and path.is_file():
            digest.update(str(path).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def _module_file(name: str) -> str | None:
    """The file of module ``name``, whether or not this process has imported it yet (a key that counted it
    only once imported differed between ``hetros hw bitstream``, which builds the nodes, and a benchmark
    reading the clock that run recorded)."""
    module = sys.modules.get(name)
    if module is not None:
        return getattr(module, "__file__", None)
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    return spec.origin if spec is not None and spec.has_location else None


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


def record_fmax(key: str, fmax_mhz: float, device: str, critical_path: str, nodes_alone: bool = False) -> None:
    """Remember what place and route achieved for the design ``key`` (``hetros hw bitstream``).

    ``nodes_alone``: the figure is the slowest of the target's nodes placed one at a time (``--parts
    parts``, or a target too big for any ECP5), an upper bound of the whole target's clock. It never
    replaces the record of the whole target placed as one design, which is the better figure."""
    path = _fmax_file(key)
    if nodes_alone and _read_record(key).get("scope") == "target":
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    record = {"fmax_mhz": fmax_mhz, "device": device, "critical_path": critical_path,
              "scope": "nodes alone" if nodes_alone else "target",
              "measured": time.strftime("%Y-%m-%d %H:%M", time.localtime())}
    temporary = path.with_suffix(f".{os.getpid()}.tmp")
    temporary.write_text(json.dumps(record), encoding="utf-8")
    temporary.replace(path)


def target_clock(plan: Plan, target: str, key: str | None = None) -> TargetClock:
    """The lower of the target's ``clock_mhz`` and the Fmax last measured for this very design."""
    wanted = plan.targets[target].clock_mhz
    record = _read_record(key or target_key(plan, target))
    try:
        fmax = float(str(record["fmax_mhz"]))
        measured, device = str(record.get("measured", "")), str(record.get("device", "ECP5"))
    except (ValueError, KeyError, TypeError):
        return TargetClock(wanted, "clock_mhz; no `hetros hw bitstream` of this design yet")
    if not fmax > 0:
        return TargetClock(wanted, "clock_mhz; the recorded Fmax is not a clock")
    alone = record.get("scope") == "nodes alone"
    where = f"its slowest node placed alone on {device}" if alone else device
    bound = ("; an upper bound: the whole target has not been placed as one design (`hetros hw bitstream` without "
             "--parts)") if alone else ""
    if fmax < wanted:
        return TargetClock(fmax, f"the Fmax place and route achieved on {where} ({measured}), below clock_mhz "
                                 f"{wanted:g}{bound}")
    return TargetClock(wanted, f"clock_mhz, which place and route met on {where} ({measured}: {fmax:.1f} MHz)"
                               f"{bound}")


def _read_record(key: str) -> dict[str, object]:
    """The record of ``key``; empty where there is none or it is damaged (then it is no figure)."""
    try:
        record = json.loads(_fmax_file(key).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return record if isinstance(record, dict) else {}
