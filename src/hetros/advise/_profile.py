"""The profile: what the advisor's model knows of a project, measured once and kept as a file.

Per node and input topic the node's time per message (its thread's CPU time while profiling, so that
waiting for a shared core or the GIL is not counted as work) as quantiles, as mapped and with every
node in one process on one core (``one_core``: a node right after its publisher on the same awake
core runs faster than on a core it wakes from idle), and which outputs it publishes per message of
that input; per source (a node that publishes from a loop or a timer) its CPU per message; per topic
its rate and size; per process its CPU share; per chain its measured latency. The profile names the
project's graph (not its mapping) and the machine, so that advice from it can be recomputed without
running again, and a profile from elsewhere is noticed.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from .._errors import AdviseError
from .._files import dataclass_problem, load_json
from ..plan import Plan
from ..runtime import HandlingStats
from ._chains import Chain, ChainLatency, measure, over_launches
from ._observe import Observation

FORMAT = 1


def machine() -> dict[str, Any]:
    """What a profile's and a calibration's figures depend on: the host, its CPU model and count."""
    model = ""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        model = platform.processor()
    return {"host": platform.node(), "cpu": model, "cpus": len(os.sched_getaffinity(0)), "hetros": __version__}


def cpu_mhz() -> float:
    """The CPUs' mean clock now (``/proc/cpuinfo``; 0.0 where it does not say): a calibration's condition."""
    try:
        lines = Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines()
        clocks = [float(line.split(":", 1)[1]) for line in lines if line.startswith("cpu MHz")]
    except (OSError, ValueError):
        return 0.0
    return round(sum(clocks) / len(clocks), 1) if clocks else 0.0


def graph_key(plan: Plan) -> str:
    """The project's graph apart from its mapping: nodes, what they run, their topics and parameters."""
    nodes = {name: [spec.run, spec.hw, sorted(spec.publish.items()), sorted(spec.subscribe.items()),
                    json.dumps(spec.parameters, sort_keys=True, default=str)]
             for name, spec in sorted(plan.nodes.items()) if not _system(plan, name)}
    return hashlib.sha256(json.dumps([plan.name, nodes], sort_keys=True).encode()).hexdigest()[:16]


def _system(plan: Plan, node: str) -> bool:
    """A node the planner added (a gateway, a bridge, the clock follower): never moved on its own."""
    return plan.nodes[node].run.startswith("hetros.")


@dataclass
class Handling:
    """A node's time per message of one input: mean and quantiles (ms) at ``points`` (fractions);
    CPU time when ``cpu``."""

    count: int
    mean_ms: float
    quantiles_ms: list[float]
    cpu: bool
    points: list[float] = field(default_factory=lambda: list(HandlingStats.POINTS))


@dataclass
class NodeProfile:
    process: str
    cpus: list[int]
    handling: dict[str, Handling] = field(default_factory=dict)
    # per input topic ("" for a loop or timer): per output topic, messages published per message handled
    triggers: dict[str, dict[str, float]] = field(default_factory=dict)
    cpu_share: float = 0.0  # of one core, over the window
    hardware: dict[str, Any] = field(default_factory=dict)
    # per input topic, the time per message in a launch with every node in one process pinned to one core: a
    # node right after its publisher on the same awake core runs warm (ball on plate's control 221 against
    # 284 µs, 2026-11-29)
    one_core: dict[str, Handling] = field(default_factory=dict)


@dataclass
class TopicProfile:
    type: str
    rate_hz: float
    size_bytes: int
    publishers: list[str]
    subscribers: list[str]


@dataclass
class Profile:
    project: str
    graph: str
    machine: dict[str, Any]
    window_s: float
    mapping: dict[str, str]
    nodes: dict[str, NodeProfile]
    topics: dict[str, TopicProfile]
    processes: dict[str, float]  # CPU share of one core per process
    chains: dict[str, dict[str, Any]] = field(default_factory=dict)
    one_core_chains: dict[str, dict[str, Any]] = field(default_factory=dict)  # the chains in the one-core launch
    format: int = FORMAT

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(asdict(self), indent=1) + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: Path) -> Profile:
        raw = load_json(path, "profile", error=AdviseError)
        if not isinstance(raw, dict) or raw.get("format") != FORMAT:
            raise AdviseError(f"{path}: a profile of format {FORMAT} expected, not "
                              f"{raw.get('format') if isinstance(raw, dict) else type(raw).__name__!r}; profile again")
        try:
            nodes = {name: NodeProfile(**{**spec, "handling": {t: Handling(**h) for t, h in spec["handling"].items()},
                                          "one_core": {t: Handling(**h) for t, h in spec.get("one_core", {}).items()}})
                     for name, spec in raw["nodes"].items()}
            topics = {name: TopicProfile(**spec) for name, spec in raw["topics"].items()}
            profile = cls(**{**raw, "nodes": nodes, "topics": topics})
        except (KeyError, TypeError, AttributeError, ValueError) as exc:
            raise AdviseError(f"{path}: a damaged profile ({exc!r}); profile again") from None
        problem = dataclass_problem(profile, "profile")
        if problem is not None:
            raise AdviseError(f"{path}: a damaged profile ({problem}); profile again")
        return profile

    def fits(self, plan: Plan) -> list[str]:
        """Why this profile may not describe ``plan`` on this machine: warnings, empty when it does."""
        warnings = []
        if self.graph != graph_key(plan):
            warnings.append(f"the profile is of another graph (project {self.project!r}, graph {self.graph}; this one "
                            f"is {plan.name!r}, graph {graph_key(plan)}): nodes, code or topics changed since; "
                            "profile again for advice that fits")
        here = machine()
        changed = [f"{key} {self.machine.get(key)!r} -> {here[key]!r}" for key in ("host", "cpu", "cpus")
                   if self.machine.get(key) != here[key]]
        if changed:
            warnings.append(f"the profile was measured on another machine ({'; '.join(changed)}): the node times are "
                            "that machine's; the transport costs are recalibrated here (`--calibrate`)")
        return warnings


def _quantiles_ms(handling: dict[str, Any]) -> tuple[list[float], bool]:
    cpu = handling.get("cpu_quantiles_s")
    chosen = cpu if cpu else handling.get("quantiles_s") or [handling.get("p50_s", 0.0)] * len(HandlingStats.POINTS)
    return [float(v) * 1000.0 for v in chosen], bool(cpu)


def _handling(early: dict[str, Any] | None, late: dict[str, Any]) -> Handling:
    """A node's time on one input from the figures at the warm-up's end and at the end."""
    quantiles, cpu = _quantiles_ms(late)
    key_count, key_total = ("cpu_count", "cpu_total_s") if cpu else ("count", "total_s")
    count = int(late.get(key_count, 0)) - int((early or {}).get(key_count, 0))
    total = float(late.get(key_total, 0.0)) - float((early or {}).get(key_total, 0.0))
    if count <= 0:  # nothing new after the warm-up: the figures of the whole run
        count, total = int(late.get(key_count, 0)), float(late.get(key_total, 0.0))
    mean = total / count * 1000.0 if count else float(np.mean(quantiles))
    return Handling(count, mean, quantiles, cpu)


def build(observation: Observation, chains: list[Chain]) -> Profile:
    """The profile of one watched run."""
    plan, window = observation.plan, observation.window_s
    topics = {}
    for name, channel in plan.channels.items():
        if channel.kind != "topic":
            continue
        events = observation.published.get(name, [])
        size = int(np.median([p.size for p in events])) if events else 0
        topics[name] = TopicProfile(channel.type, len(events) / window, size, list(channel.publishers),
                                    list(channel.subscribers))
    nodes: dict[str, NodeProfile] = {}
    processes: dict[str, float] = {}
    for process, late in observation.late.items():
        early = observation.early.get(process, {})
        processes[process] = max(0.0, (late["cpu_s"] - early.get("cpu_s", late["cpu_s"])) / window)
        for name, figures in late["nodes"].items():
            if name not in plan.nodes or _system(plan, name):
                continue
            before = early.get("nodes", {}).get(name, {})
            handling = {topic: _handling(before.get("handling", {}).get(topic), h)
                        for topic, h in figures["handling"].items() if h.get("count")}
            cpus = list(plan.targets[plan.nodes[name].target].cpus)
            nodes[name] = NodeProfile(plan.process_of(name), cpus, handling, _triggers(figures, topics),
                                      max(0.0, (figures["cpu_s"] - before.get("cpu_s", figures["cpu_s"])) / window))
    latencies = chain_latencies(observation, chains)
    measured = {chain.name: {"first": chain.first, "last": chain.last, **latency.as_dict()}
                for chain in chains if (latency := latencies[chain.name]) is not None}
    return Profile(plan.name, graph_key(plan), machine(), window,
                   {n: plan.nodes[n].target for n in plan.nodes if not _system(plan, n)}, nodes, topics, processes,
                   measured)


def pooled(profiles: list[Profile], observations: list[Observation], chains: list[Chain]) -> Profile:
    """One profile of several launches of one mapping (``--rounds``): per node and input the quantiles
    averaged point by point (a pooled distribution's shape, each launch weighing the same) and the
    counts added; rates, CPU shares and the window averaged; each chain the median of the launches'
    p50s and p99s. The model is fitted on the profile's chains (the wake scale), so one slow launch
    would otherwise move every prediction: a sub-millisecond chain measured 0.75 and 1.0 ms in two
    launches of one mapping."""
    if len(profiles) == 1:
        return profiles[0]
    first = profiles[0]
    nodes: dict[str, NodeProfile] = {}
    for name, spec in first.nodes.items():
        each = [p.nodes[name] for p in profiles if name in p.nodes]
        handling = {}
        for topic in spec.handling:
            found = [n.handling[topic] for n in each if topic in n.handling]
            count = sum(h.count for h in found)
            mean = sum(h.mean_ms * h.count for h in found) / count if count else \
                float(np.mean([h.mean_ms for h in found]))
            shape = [float(v) for v in np.mean([h.quantiles_ms for h in found], axis=0)]
            handling[topic] = Handling(count, mean, shape, spec.handling[topic].cpu, list(spec.handling[topic].points))
        nodes[name] = NodeProfile(spec.process, spec.cpus, handling, spec.triggers,
                                  float(np.mean([n.cpu_share for n in each])), spec.hardware)
    topics = {name: TopicProfile(spec.type, float(np.mean([p.topics[name].rate_hz for p in profiles])),
                                 int(np.median([p.topics[name].size_bytes for p in profiles])), spec.publishers,
                                 spec.subscribers) for name, spec in first.topics.items()}
    processes = {name: float(np.mean([p.processes.get(name, share) for p in profiles]))
                 for name, share in first.processes.items()}
    measured = {}
    for chain in chains:
        latency = over_launches([chain_latencies(seen, [chain])[chain.name] for seen in observations])
        if latency is not None:
            measured[chain.name] = {"first": chain.first, "last": chain.last, **latency.as_dict()}
    return Profile(first.project, first.graph, first.machine, float(np.mean([p.window_s for p in profiles])),
                   first.mapping, nodes, topics, processes, measured)


def with_one_core(profile: Profile, one_core: Profile) -> Profile:
    """``profile`` with the node times and chains of ``one_core``, a profile of the same graph launched with
    every process on one core."""
    for name, spec in profile.nodes.items():
        other = one_core.nodes.get(name)
        spec.one_core = dict(other.handling) if other is not None else {}
    profile.one_core_chains = dict(one_core.chains)
    return profile


def _triggers(figures: dict[str, Any], topics: dict[str, TopicProfile]) -> dict[str, dict[str, float]]:
    """Per input, what the node published per message of it (both counted over the whole run); for a
    loop's or timer's publishes (input ""), per second: its share of the topic's rate."""
    counts: dict[tuple[str, str], int] = {(c, t): n for c, t, n in figures.get("triggers", [])}
    triggers: dict[str, dict[str, float]] = {}
    for (cause, topic), count in counts.items():
        if cause:
            handled = int(figures["handling"].get(cause, {}).get("count", 0))
            triggers.setdefault(cause, {})[topic] = count / handled if handled else 0.0
        else:
            total = sum(n for (_, t), n in counts.items() if t == topic)
            rate = topics[topic].rate_hz if topic in topics else 0.0
            triggers.setdefault(cause, {})[topic] = rate * count / total
    return triggers


def chain_latencies(observation: Observation, chains: list[Chain]) -> dict[str, ChainLatency | None]:
    return {chain.name: measure(observation.published.get(chain.first, []), observation.published.get(chain.last, []))
            for chain in chains}
