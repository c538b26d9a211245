"""Chains: a named path from a first topic to a last one, and its latency measured from taps.

A chain's latency is the time from a message's publish on the first topic to the publish, on
the last topic, of what became of it. Where both topics carry a ``std_msgs/Header`` and the
nodes hand its stamp on (what ROS code does, and what ``message_filters`` relies on), the two
publishes are matched by stamp; where they do not, each message on the last topic is matched
with the newest one on the first topic published before it, which is exact while the chain
is faster than the first topic's period and says so in the result.
"""

from __future__ import annotations

import bisect
import re
import statistics
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .._errors import AdviseError
from ..plan import SYSTEM_NODES, Plan

_CHAIN = re.compile(r"(?:(?P<name>[A-Za-z_][\w-]*)=)?(?P<first>/?[^:@\s]+):(?P<last>/?[^:@\s]+)"
                    r"(?:@(?P<deadline>[0-9.]+)\s*ms)?")


@dataclass(frozen=True)
class Chain:
    """From ``first`` topic to ``last`` topic, with an optional deadline on its latency (ms)."""

    name: str
    first: str
    last: str
    deadline_ms: float | None = None

    @classmethod
    def parse(cls, text: str) -> Chain:
        """``[name=]/first:/last[@30ms]`` (what ``hetros advise --chain`` takes)."""
        found = _CHAIN.fullmatch(text.strip())
        if found is None:
            raise AdviseError(f"a chain must be written [name=]/first_topic:/last_topic[@DEADLINEms], "
                              f"not {text!r} (for example alpha=/image_raw:/cmd_vel@30ms)")
        deadline = float(found["deadline"]) if found["deadline"] else None
        if deadline is not None and not deadline > 0:
            raise AdviseError(f"a chain's deadline must be a positive number of ms, not {found['deadline']!r}")
        first, last = found["first"], found["last"]
        return cls(found["name"] or f"{first}->{last}", first, last, deadline)

    def check(self, plan: Plan) -> list[str]:
        """The nodes the chain passes through (each on some path from the first topic's subscribers to the
        last topic's publishers), nearest the first topic first; AdviseError naming the topics where no
        path leads from the first topic to the last."""
        topics = sorted(n for n, c in plan.channels.items() if c.kind == "topic")
        for topic in (self.first, self.last):
            if topic not in plan.channels or plan.channels[topic].kind != "topic":
                raise AdviseError(f"chain {self.name}: the project has no topic {topic} (its topics: "
                                  f"{', '.join(topics)})")
        forward = _reach(plan, self.first, downstream=True)
        backward = _reach(plan, self.last, downstream=False)
        nodes = [n for n in forward if n in backward]
        if not nodes:
            raise AdviseError(f"chain {self.name}: no node path leads from {self.first} to {self.last}: nothing "
                              f"that subscribes {self.first} publishes, through other nodes, {self.last}")
        return nodes


def _reach(plan: Plan, topic: str, *, downstream: bool) -> dict[str, int]:
    """The nodes reachable from ``topic`` (downstream: through subscribers and what they publish;
    upstream: through publishers and what they subscribe), with their distance in nodes."""
    found: dict[str, int] = {}
    frontier, seen, distance = [topic], {topic}, 0
    while frontier:
        distance += 1
        following = []
        for name in frontier:
            channel = plan.channels.get(name)
            if channel is None:
                continue
            for node in channel.subscribers if downstream else channel.publishers:
                if node in found or node not in plan.nodes:
                    continue
                found[node] = distance
                spec = plan.nodes[node]
                for out in spec.publish if downstream else spec.subscribe:
                    if out not in seen:
                        seen.add(out)
                        following.append(out)
        frontier = following
    return found


@dataclass(frozen=True)
class Published:
    """One publish a tap saw: wall time (ns), encoded size, header stamp (ns) when there is one."""

    time_ns: int
    size: int
    stamp: int | None


@dataclass(frozen=True)
class ChainLatency:
    """A chain's measured latency: p50 and p99 in ms over ``samples`` messages, and how they were matched."""

    p50_ms: float
    p99_ms: float
    samples: int
    matched_by: str
    values_ms: tuple[float, ...] = ()
    launch_p50s_ms: tuple[float, ...] = ()  # each launch's p50, where this is the median of several

    def as_dict(self) -> dict[str, object]:
        found: dict[str, object] = {"p50_ms": self.p50_ms, "p99_ms": self.p99_ms, "samples": self.samples,
                                    "matched_by": self.matched_by}
        if self.launch_p50s_ms:
            found["launch_p50s_ms"] = list(self.launch_p50s_ms)
        return found


def over_launches(launches: list[ChainLatency | None]) -> ChainLatency | None:
    """One chain's latency over several launches of one mapping: the median of their p50s and of their
    p99s. A chain under a millisecond differs from launch to launch by more than the advisor's 20 %
    (where the scheduler puts each process's threads, what else runs), so one launch is one draw."""
    measured = [launch for launch in launches if launch is not None]
    if len(measured) <= 1:
        return measured[0] if measured else None
    return ChainLatency(statistics.median(m.p50_ms for m in measured), statistics.median(m.p99_ms for m in measured),
                        sum(m.samples for m in measured), measured[0].matched_by,
                        tuple(v for m in measured for v in m.values_ms), tuple(m.p50_ms for m in measured))


def measure(first: list[Published], last: list[Published]) -> ChainLatency | None:
    """The latencies from ``first``'s publishes to ``last``'s (both in time order); None when no
    message on ``last`` follows one on ``first``."""
    stamped = [p for p in first if p.stamp] and [p for p in last if p.stamp]
    values: list[float] = []
    if stamped:
        sent: dict[int, int] = {}
        for published in first:
            if published.stamp:
                sent.setdefault(published.stamp, published.time_ns)
        values = [(p.time_ns - sent[p.stamp]) / 1e6 for p in last
                  if p.stamp in sent and p.time_ns >= sent[p.stamp]]
    matched_by = "header stamp"
    if not values:
        matched_by = "newest message on the first topic before it"
        times = [p.time_ns for p in first]
        for published in last:
            at = bisect.bisect_right(times, published.time_ns)
            if at:
                values.append((published.time_ns - times[at - 1]) / 1e6)
    if not values:
        return None
    array = np.asarray(values)
    return ChainLatency(float(np.percentile(array, 50)), float(np.percentile(array, 99)), len(values), matched_by,
                        tuple(values))


@dataclass(frozen=True)
class HardwareSpan:
    """One message's time in an fpga target, as its gateway counted it (``CoSimulatedTimes``): in simulated
    time at the target's clock, and the CPU time the gateway spent copying it in and out."""

    sim_ns: float
    cpu_ns: float


def cosimulated_latency(plan: Plan, chain: Chain, published: dict[str, list[Published]],
                        spans: dict[tuple[str, int], HardwareSpan], hop_ns: Callable[[str, int], float]
                        ) -> ChainLatency | None:
    """The chain's latency with its hardware in co-simulated time, per header stamp.

    A co-simulation runs slower than the hardware would, so in wall time messages wait for the simulator.
    Here each topic's publish is placed in co-simulated time along the chain: a hardware node's output at
    the latest of its target's inputs, plus a shared-memory hop into the gateway (``hop_ns(topic, size)``),
    the gateway's copies and the simulated span; a software node's output at the latest of its inputs, plus
    what it took in wall time (from its last input's publish to its own: the hop and its work, measured).
    Stamps that did not reach every topic on the way are left out. None when no stamp went through.
    """
    gateway = SYSTEM_NODES["gateway"]
    nodes = [n for n in chain.check(plan) if plan.nodes[n].run != gateway]  # its hardware nodes stand for it
    times: dict[str, dict[int, Published]] = {}
    for topic, events in published.items():
        by_stamp: dict[int, Published] = {}
        for event in events:
            if event.stamp:
                by_stamp.setdefault(event.stamp, event)
        times[topic] = by_stamp
    reachable = {chain.first} | {t for n in nodes for t in plan.nodes[n].publish}
    gateway_inputs = {t for spec in plan.nodes.values() if spec.run == gateway for t in spec.subscribe}
    values: list[float] = []
    for stamp in times.get(chain.first, {}):
        placed: dict[str, float] = {chain.first: 0.0}
        waiting = list(nodes)
        while waiting:  # a node is placed once every input of it this stamp reached is (the graph is acyclic)
            ready = [n for n in waiting if all(t in placed for t in plan.nodes[n].subscribe
                                               if t in reachable and stamp in times.get(t, {}))]
            if not ready:
                break
            for node in ready:
                waiting.remove(node)
                _place(plan, node, stamp, times, placed, spans, gateway_inputs, hop_ns)
        if chain.last in placed and chain.last != chain.first:
            values.append(placed[chain.last] / 1e6)
    if not values:
        return None
    array = np.asarray(values)
    return ChainLatency(float(np.percentile(array, 50)), float(np.percentile(array, 99)), len(values),
                        "header stamp; hardware in co-simulated time", tuple(values))


def _place(plan: Plan, node: str, stamp: int, times: dict[str, dict[int, Published]], placed: dict[str, float],
           spans: dict[tuple[str, int], HardwareSpan], gateway_inputs: set[str],
           hop_ns: Callable[[str, int], float]) -> None:
    """Place ``node``'s outputs of ``stamp`` in co-simulated time (ns after the chain's first publish)."""
    spec = plan.nodes[node]
    inputs = [t for t in spec.subscribe if t in placed and stamp in times.get(t, {})]
    if not inputs:
        return
    for topic in spec.publish:
        out = times.get(topic, {}).get(stamp)
        if out is None or topic in placed:
            continue
        if plan.in_hardware(node):
            span = spans.get((topic, stamp))
            entering = [t for t in placed if t in gateway_inputs and stamp in times.get(t, {})]
            if span is not None and entering:
                placed[topic] = max(placed[t] + hop_ns(t, times[t][stamp].size) for t in entering) \
                    + span.cpu_ns + span.sim_ns
        else:
            latest = max(inputs, key=lambda t: times[t][stamp].time_ns)
            placed[topic] = max(placed[t] for t in inputs) + (out.time_ns - times[latest][stamp].time_ns)
