"""The advice, told: a table of the best mappings, the chosen one as a project file, and the
predicted timeline of one message through each chain as a picture."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from .._errors import AdviseError
from .._files import load_yaml
from ._chains import Chain
from ._model import Mapping, Placement
from ._profile import Profile
from ._search import Candidate, Limits


def target_names(candidate: Mapping, original: Mapping, targets: dict[str, str]) -> dict[str, str]:
    """Per node the target the written project gives it: its own where it stays, the project's target
    of the same nodes on the same core where the candidate regroups nothing, else a target per core."""
    groups: dict[Placement, set[str]] = {}
    for node, placement in candidate.items():
        groups.setdefault(placement, set()).add(node)
    names = {}
    for placement, nodes in groups.items():
        same = [targets[n] for n in nodes if original[n] == placement or (
            not placement.fpga and not original[n].fpga and original[n].cpus == placement.cpus and
            {m for m, p in original.items() if p == original[n]} == nodes)]
        for node in nodes:
            names[node] = same[0] if same and len(set(same)) == 1 else placement.process
    return names


def moved(candidate: Mapping, original: Mapping, targets: dict[str, str]) -> list[str]:
    """What a candidate changes: ``node target->target``, in the names the written project would use."""
    names = target_names(candidate, original, targets)
    return [f"{node} {targets[node]}->{names[node]}" for node in sorted(candidate) if names[node] != targets[node]]


def table(rows: list[tuple[str, Candidate]], chains: list[Chain], original: Mapping, targets: dict[str, str],
          limits: Limits, profile: Profile) -> str:
    """The ranked mappings (and the project's own, for comparison) as a text table."""
    heads = ["mapping", *[f"{c.name} p50/p99 ms" + (f" (≤{c.deadline_ms:g})" if c.deadline_ms else "") for c in chains],
             "cores", "load per core", "fpga", "moved"]
    lines = []
    for label, candidate in rows:
        figures = [f"{candidate.prediction.chains[c.name].p50_ms:.1f}/{candidate.prediction.chains[c.name].p99_ms:.1f}"
                   for c in chains]
        load = " ".join(f"{share * 100:.0f}%" for _, share in sorted(candidate.prediction.core_load.items()))
        fpga = (f"{len(candidate.prediction.fpga_nodes)} nodes, {candidate.fpga_share(limits.fpga_budget, profile):.0%}"
                if candidate.prediction.fpga_nodes else "-")
        change = ", ".join(moved(candidate.mapping, original, targets)) or "(as the project maps it)"
        lines.append([label, *figures, str(candidate.cores_used()), load, fpga, change])
    widths = [max(len(str(row[i])) for row in [heads, *lines]) for i in range(len(heads) - 1)]
    out = ["  ".join(h.ljust(w) for h, w in zip(heads, [*widths, 0], strict=True)).rstrip()]
    for row in lines:
        out.append("  ".join(str(v).ljust(w) for v, w in zip(row, [*widths, 0], strict=True)).rstrip())
    out.append("ranked by each chain's p99 (over its deadline where it has one): a deadline is a worst case")
    return "\n".join(out)


def write_project(source: Path, mapping: Mapping, original: Mapping, targets: dict[str, str], out: Path) -> Path:
    """``source`` with its nodes' targets (and the targets' cpus) as ``mapping`` puts them: nothing else
    changes (comments are not kept: the file is written anew)."""
    raw = load_yaml(source, "project file", error=AdviseError)
    nodes = raw.get("nodes") if isinstance(raw, dict) else None
    if not isinstance(nodes, dict):
        raise AdviseError(f"{source}: nodes: is not a mapping of node entries; write the advised targets by hand")
    old_targets: dict[str, Any] = dict(raw.get("targets") or {})
    new_targets: dict[str, Any] = {}
    names = target_names(mapping, original, targets)
    for node, placement in mapping.items():
        entry = nodes.get(node)
        name = names[node]
        if not isinstance(entry, dict):
            raise AdviseError(f"{source}: node {node} is not an entry of nodes: (it comes from an include or a "
                              f"group); set its target by hand: {name}")
        if name in old_targets and (name == targets[node] or placement.fpga or name in targets.values()):
            new_targets[name] = old_targets[name]
        else:
            if name in old_targets and old_targets[name] != {"kind": "process", "cpus": list(placement.cpus)}:
                name = f"advised_{name}"
            new_targets[name] = {"kind": "process", "cpus": list(placement.cpus)}
        entry["target"] = name
    raw["targets"] = {name: new_targets[name] for name in [*old_targets, *sorted(new_targets)]
                      if name in new_targets}
    text = yaml.safe_dump(raw, sort_keys=False, default_flow_style=None, width=120)
    out.write_text(f"# written by `hetros advise` from {source.name}: only targets and cpus differ\n{text}",
                   encoding="utf-8")
    return out


def write_one_core(source: Path, cpu: int, out: Path) -> Path:
    """``source`` with every node of a process or thread target on this machine in one process pinned to
    ``cpu`` (the target ``advise_one_core``): the launch in which the profile measures each node right
    after its publisher on the same awake core. ROS 1, fpga and other machines' targets stay."""
    raw = load_yaml(source, "project file", error=AdviseError)
    targets, nodes = (raw.get("targets"), raw.get("nodes")) if isinstance(raw, dict) else (None, None)
    if not isinstance(targets, dict) or not isinstance(nodes, dict):
        raise AdviseError(f"{source}: targets: and nodes: must be mappings written out (not from an include) for "
                          "the profile's one-core launch")
    moving = {name for name, spec in targets.items()
              if isinstance(spec, dict) and joins_one_core(spec.get("kind"), spec.get("host"))}
    for entry in nodes.values():
        if isinstance(entry, dict) and entry.get("target") in moving:
            entry["target"] = ONE_CORE_TARGET
    used = {entry.get("target") for entry in nodes.values() if isinstance(entry, dict)}
    raw["targets"] = {name: spec for name, spec in targets.items() if name not in moving or name in used}
    raw["targets"][ONE_CORE_TARGET] = {"kind": "process", "cpus": [cpu]}
    text = yaml.safe_dump(raw, sort_keys=False, default_flow_style=None, width=120)
    out.write_text(f"# written by `hetros advise` from {source.name}: every node in one process on cpu {cpu}\n{text}",
                   encoding="utf-8")
    return out


ONE_CORE_TARGET = "advise_one_core"


def joins_one_core(kind: object, host: object) -> bool:
    """Whether the one-core launch takes a target's nodes into its one process: this machine's processes
    and threads; ROS 1, fpga and other machines' targets stay."""
    return kind in ("process", "thread") and not host


def plot_timeline(candidate: Candidate, chains: list[Chain], out: Path) -> Path:
    """Each chain's predicted way of one message (the median one): per node, waiting and working."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    drawn = [c for c in chains if candidate.prediction.chains[c.name].timeline]
    figure, axes = plt.subplots(len(drawn) or 1, 1, figsize=(9, 1.2 + 0.45 * max(
        (len(candidate.prediction.chains[c.name].timeline) for c in drawn), default=1) * max(len(drawn), 1)),
        squeeze=False)
    for axis, chain in zip(axes[:, 0], drawn, strict=False):
        hops = candidate.prediction.chains[chain.name].timeline
        for row, hop in enumerate(hops):
            axis.barh(row, hop.started - hop.arrived, left=hop.arrived, color="#f4c27a", edgecolor="none")
            axis.barh(row, hop.ended - hop.started, left=hop.started, color="#3b6fb6", edgecolor="none")
        axis.set_yticks(range(len(hops)), [f"{h.node} ({h.where})" for h in hops], fontsize=8)
        axis.invert_yaxis()
        prediction = candidate.prediction.chains[chain.name]
        axis.set_title(f"chain {chain.name}: one message, predicted p50 {prediction.p50_ms:.1f} ms "
                       "(orange: waiting for its process or core; blue: working)", fontsize=9)
        if chain.deadline_ms:
            axis.axvline(chain.deadline_ms, color="#b33", linestyle="--", linewidth=1)
        axis.set_xlabel("ms after the message's publish on " + chain.first, fontsize=8)
    figure.tight_layout()
    figure.savefig(out, dpi=110)
    plt.close(figure)
    return out
