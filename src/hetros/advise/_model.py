"""The model: a candidate mapping's chain latencies and core loads, predicted by simulating it.

A discrete-event simulation of the profiled graph under the candidate mapping, for some
seconds of its sources' periods:

- a **process** runs one node's work at a time (Python's GIL: the threads of one process take
  turns), first come first served;
- a **core** shares itself equally among the processes working on it at the moment (processor
  sharing); a process pinned to one core works there, one pinned to several or to none works
  on the least busy of them when it starts a message;
- a **node's work** per message is drawn from its profiled CPU time on that input (its quantiles,
  interpolated): as profiled, or, for a message from a node of its own process pinned to one core
  that was warm itself or a source, as profiled with every node in one process on one core (it
  runs right after its publisher on a core kept awake since the source's period began: warm); it
  then publishes what the profile says it publishes per message of it;
  a source (a loop or timer) works for its profiled CPU per period, once per period;
- an **edge** delays a message by the calibrated one-way latency of the transport the planner
  would give it at the topic's size (in one process, or shared memory between processes), and by
  the calibrated time to wake a sleeping subscriber of that kind (in a process; in another process
  on another core, or pinned to the same one core);
- a **hardware node** is its own server (its cycles per message at the target's clock); an edge
  between two hardware nodes of one target streams (the second finishes no earlier than the
  first: dataflow), an edge into or out of a target pays the gateway's copy and a shared-memory
  hop, and edges between targets go through software (sequential).

A chain's latency is the time from a publish on its first topic to the publish on its last
topic of what the first message caused, as ``_chains`` measures it in a real launch.
"""

from __future__ import annotations

import heapq
import itertools
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ._calibrate import Calibration
from ._chains import Chain
from ._profile import NodeProfile, Profile

HORIZON_S = 20.0
WARMUP_FRACTION = 0.1
MIN_PERIODS = 100


@dataclass(frozen=True)
class Placement:
    """Where a node runs: a process (threads share it), pinned to ``cpus`` (none: any core), or in
    hardware on an fpga target (``fpga``: the process name is then the target's)."""

    process: str
    cpus: tuple[int, ...] = ()
    fpga: bool = False

    def describe(self) -> str:
        if self.fpga:
            return f"fpga:{self.process}"
        return f"{self.process}@{','.join(map(str, self.cpus))}" if self.cpus else f"{self.process}@any"


Mapping = dict[str, Placement]


@dataclass(frozen=True)
class Hop:
    """One node's part in one message's way through a chain (ms from the chain's first publish)."""

    node: str
    where: str
    arrived: float
    started: float
    ended: float


@dataclass
class ChainPrediction:
    p50_ms: float
    p99_ms: float
    samples: int
    timeline: list[Hop] = field(default_factory=list)
    # per node on the chain: mean ms waiting (for its process or core) and working
    waiting_ms: dict[str, float] = field(default_factory=dict)
    working_ms: dict[str, float] = field(default_factory=dict)

    def dominant(self) -> str:
        """The node whose waiting and working take most of the chain's time."""
        totals = {n: self.waiting_ms.get(n, 0.0) + self.working_ms.get(n, 0.0) for n in self.working_ms}
        return max(totals, key=lambda n: totals[n]) if totals else "-"


@dataclass
class Prediction:
    chains: dict[str, ChainPrediction]
    core_load: dict[int, float]
    fpga_nodes: list[str]


class _Sampler:
    """Draws a node's time per message from its quantiles (a piecewise-linear inverse CDF)."""

    def __init__(self, quantiles_ms: list[float], points: list[float], rng: np.random.Generator) -> None:
        self.values = np.asarray(quantiles_ms, dtype=np.float64)
        self.points = np.asarray(points, dtype=np.float64) if len(points) == len(self.values) else \
            np.linspace(0.0, 1.0, len(self.values))
        self.rng = rng
        self._batch: list[float] = []

    def draw(self) -> float:
        if not self._batch:
            self._batch = list(np.interp(self.rng.random(256), self.points, self.values))
        return max(0.0, self._batch.pop())


@dataclass
class _Job:
    node: str
    topic: str  # the input ("" for a source's period)
    origins: dict[str, float]
    trace: tuple[Any, ...] | None  # (parent trace, (node, where, arrived)) while on a chain
    arrived: float
    ticks: dict[str, int] = field(default_factory=dict)  # per source node, which of its periods began this
    # its input came from a node of its process, pinned to one core, that was a source or warm itself
    warm: bool = False
    overlap: float = 0.0  # streamed in from hardware upstream: the time it already worked beside it
    work: float = 0.0
    started: float = 0.0
    core: int = -1


class Simulation:
    """One candidate mapping, simulated; ``run`` gives the prediction."""

    def __init__(self, profile: Profile, calibration: Calibration, mapping: Mapping, chains: list[Chain],
                 cores: int, *, seed: int = 1, horizon_s: float = HORIZON_S) -> None:
        self.profile = profile
        self.calibration = calibration
        self.mapping = mapping
        self.chains = chains
        self.cores = cores
        self.rng = np.random.default_rng(seed)
        self.now = 0.0
        self.events: list[tuple[float, int, str, _Job]] = []
        self._order = itertools.count()
        self.queues: dict[str, deque[_Job]] = {}
        self.busy: dict[str, _Job | None] = {}
        self.running: dict[int, list[_Job]] = {c: [] for c in range(cores)}
        self.served: dict[int, float] = dict.fromkeys(range(cores), 0.0)
        self.samplers: dict[tuple[str, str, bool], _Sampler] = {}
        self.carry: dict[tuple[str, str, str], float] = {}
        self.firsts = {c.first for c in chains}
        self.by_last: dict[str, list[Chain]] = {}
        for chain in chains:
            self.by_last.setdefault(chain.last, []).append(chain)
        self.samples: dict[str, list[tuple[float, tuple[Any, ...] | None]]] = {c.name: [] for c in chains}
        self.joins, self.sources_of = _joins(profile)
        self.pending: dict[tuple[str, str, str, int], set[str]] = {}
        periods = [1.0 / rate for node in profile.nodes.values() for rate in node.triggers.get("", {}).values()
                   if rate > 0]
        self.horizon = max(horizon_s, MIN_PERIODS * max(periods, default=0.0)) * 1000.0
        self.warmup = self.horizon * WARMUP_FRACTION

    # -- the graph --------------------------------------------------------------------------

    def _placement(self, node: str) -> Placement:
        return self.mapping[node]

    def _work(self, node: str, topic: str, warm: bool) -> float:
        spec = self.profile.nodes[node]
        place = self._placement(node)
        if place.fpga:
            return float(spec.hardware.get("ms", 0.0))
        if not topic:
            return _source_work(spec, self.profile.window_s)
        key = (node, topic, warm)
        sampler = self.samplers.get(key)
        if sampler is None:
            handling = spec.handling.get(topic)
            if warm:
                handling = spec.one_core.get(topic, handling)
            sampler = self.samplers[key] = _Sampler(handling.quantiles_ms if handling else [0.0],
                                                    handling.points if handling else [0.0], self.rng)
        return sampler.draw()

    def _delay(self, publisher: str, subscriber: str, topic: str) -> float:
        """The edge's one-way latency (ms); a stream between hardware nodes of one target takes none."""
        sender, receiver = self._placement(publisher), self._placement(subscriber)
        size = self.profile.topics[topic].size_bytes if topic in self.profile.topics else 0
        if sender.fpga and receiver.fpga and sender.process == receiver.process:
            return 0.0
        delay = 0.0
        if sender.fpga or receiver.fpga:  # the gateway's copy, and its hop to or from the node's process
            delay += self.calibration.latency_ms("copy", size) * (int(sender.fpga) + int(receiver.fpga))
            if sender.fpga and receiver.fpga:
                return delay + self.calibration.hop_ms("shm", size)
        if sender.process == receiver.process and not (sender.fpga or receiver.fpga):
            return delay + self.calibration.hop_ms("inproc", size, warm=len(sender.cpus) == 1)
        # two processes pinned to one core: the wake switches that core over rather than waking another
        one_core = len(sender.cpus) == 1 and sender.cpus == receiver.cpus and not (sender.fpga or receiver.fpga)
        return delay + self.calibration.hop_ms("shm", size, "shm_one_core" if one_core else "shm")

    # -- events -----------------------------------------------------------------------------

    def _schedule(self, at: float, kind: str, job: _Job) -> None:
        heapq.heappush(self.events, (at, next(self._order), kind, job))

    def _arrive(self, job: _Job) -> None:
        place = self._placement(job.node)
        server = job.node if place.fpga else place.process
        queue = self.queues.setdefault(server, deque())
        queue.append(job)
        if self.busy.get(server) is None:
            self._start(server)

    def _start(self, server: str) -> None:
        queue = self.queues[server]
        if not queue:
            self.busy[server] = None
            return
        job = queue.popleft()
        self.busy[server] = job
        job.started = self.now
        job.work = self._work(job.node, job.topic, job.warm)
        place = self._placement(job.node)
        if place.fpga:
            job.started -= min(job.overlap, job.work)
            self._schedule(self.now + max(job.work - job.overlap, 0.0), "done", job)
            return
        allowed = [c for c in (place.cpus or range(self.cores)) if c < self.cores] or list(range(self.cores))
        job.core = min(allowed, key=lambda c: len(self.running[c]))
        self.running[job.core].append(job)

    def _finish(self, job: _Job) -> None:
        place = self._placement(job.node)
        server = job.node if place.fpga else place.process
        self.busy[server] = None
        trace = job.trace
        if trace is not None or job.origins:
            trace = (trace, (job.node, place.describe(), job.arrived, job.started, self.now))
        self._publish(job, trace)
        self._start(server)

    def _publish(self, job: _Job, trace: tuple[Any, ...] | None) -> None:
        spec = self.profile.nodes[job.node]
        for topic, inputs in self.joins.get(job.node, {}).items():
            if job.topic in inputs:
                self._join(job, topic, inputs, trace)
        outputs = {t: per for t, per in spec.triggers.get(job.topic, {}).items()
                   if t not in self.joins.get(job.node, {})}
        for topic, per in outputs.items():
            if not job.topic:  # a source publishes its topics at their own rates, per its period
                per = per / _source_rate(spec)
            key = (job.node, job.topic, topic)
            carried = self.carry.get(key, 0.0) + per
            while carried >= 1.0 - 1e-9:
                carried -= 1.0
                self._send(job, topic, trace)
            self.carry[key] = carried

    def _join(self, job: _Job, topic: str, inputs: frozenset[str], trace: tuple[Any, ...] | None) -> None:
        """A joining node's input: once every input of the same source period was handled, publish."""
        shared = sorted(set(job.ticks) & self.sources_of[(job.node, topic)])
        if not shared:
            return
        key = (job.node, topic, shared[0], job.ticks[shared[0]])
        seen = self.pending.setdefault(key, set())
        seen.add(job.topic)
        if seen >= inputs:
            del self.pending[key]
            self._send(job, topic, trace)

    def _send(self, job: _Job, topic: str, trace: tuple[Any, ...] | None) -> None:
        origins = dict(job.origins)
        if topic in self.firsts:
            origins[topic] = self.now
            trace = None
        for chain in self.by_last.get(topic, ()):
            sent = origins.get(chain.first)
            if sent is not None and self.now >= self.warmup:
                self.samples[chain.name].append((self.now - sent, trace))
        if not origins:
            trace = None
        topic_profile = self.profile.topics.get(topic)
        if topic_profile is None:
            return
        for subscriber in topic_profile.subscribers:
            reader = self.profile.nodes.get(subscriber)
            if reader is None or subscriber not in self.mapping or topic not in reader.handling:
                continue  # a system node, or a subscriber that never took the topic while profiled
            at = self.now + self._delay(job.node, subscriber, topic)
            sender, receiver = self._placement(job.node), self._placement(subscriber)
            # a wake across processes or cores leaves the next node's core cold, and what follows it there
            warm = sender == receiver and len(receiver.cpus) == 1 and not receiver.fpga and (job.warm or not job.topic)
            follower = _Job(subscriber, topic, origins, trace, at, dict(job.ticks), warm=warm)
            if sender.fpga and receiver.fpga and sender.process == receiver.process:
                follower.overlap = self.now - job.started  # dataflow: it worked beside its upstream node
            self._schedule(at, "arrive", follower)

    def _advance(self, until: float) -> None:
        """Serve the running jobs up to ``until`` (each core shared equally among its jobs)."""
        span = until - self.now
        for core, jobs in self.running.items():
            if jobs and span > 0:
                share = span / len(jobs)
                for job in jobs:
                    job.work -= share
                self.served[core] += span
        self.now = until

    def _next_completion(self) -> tuple[float, _Job | None]:
        best, found = float("inf"), None
        for jobs in self.running.values():
            if jobs:
                job = min(jobs, key=lambda j: j.work)
                at = self.now + max(job.work, 0.0) * len(jobs)
                if at < best:
                    best, found = at, job
        return best, found

    def run(self) -> Prediction:
        for node, spec in self.profile.nodes.items():
            rate = _source_rate(spec)
            if rate > 0 and node in self.mapping:
                period = 1000.0 / rate
                for number, tick in enumerate(np.arange(0.0, self.horizon, period)):
                    self._schedule(float(tick), "arrive", _Job(node, "", {}, None, float(tick), {node: number}))
        while True:
            next_event = self.events[0][0] if self.events else float("inf")
            completion, job = self._next_completion()
            if min(next_event, completion) > self.horizon:
                break
            if job is not None and completion <= next_event:
                self._advance(completion)
                self.running[job.core].remove(job)
                self._finish(job)
                continue
            at, _, kind, event_job = heapq.heappop(self.events)
            self._advance(at)
            if kind == "arrive":
                self._arrive(event_job)
            else:
                self._finish(event_job)
        return self._prediction()

    def _prediction(self) -> Prediction:
        chains = {}
        for chain in self.chains:
            found = self.samples[chain.name]
            if not found:
                chains[chain.name] = ChainPrediction(float("inf"), float("inf"), 0)
                continue
            values = np.asarray([v for v, _ in found])
            prediction = ChainPrediction(float(np.percentile(values, 50)), float(np.percentile(values, 99)),
                                         len(values))
            median = int(np.argsort(values)[len(values) // 2])
            prediction.timeline = _hops(found[median][1], found[median][0])
            waiting: dict[str, list[float]] = {}
            working: dict[str, list[float]] = {}
            for _, trace in found:
                for hop in _hops(trace, 0.0):
                    waiting.setdefault(hop.node, []).append(hop.started - hop.arrived)
                    working.setdefault(hop.node, []).append(hop.ended - hop.started)
            prediction.waiting_ms = {n: float(np.mean(v)) for n, v in waiting.items()}
            prediction.working_ms = {n: float(np.mean(v)) for n, v in working.items()}
            chains[chain.name] = prediction
        load = {core: served / self.horizon for core, served in self.served.items()}
        return Prediction(chains, load, sorted(n for n, p in self.mapping.items() if p.fpga))


JOIN_RATE_TOLERANCE = 0.1


def _upstream_sources(profile: Profile) -> dict[str, set[str]]:
    """Per topic, the source nodes (loops, timers) whose periods its messages follow."""
    found: dict[str, set[str]] = {t: set() for t in profile.topics}
    for node, spec in profile.nodes.items():
        for topic in spec.triggers.get("", {}):
            found.setdefault(topic, set()).add(node)
    changed = True
    while changed:
        changed = False
        for spec in profile.nodes.values():
            for cause, outputs in spec.triggers.items():
                if not cause:
                    continue
                for topic in outputs:
                    before = len(found.setdefault(topic, set()))
                    found[topic] |= found.get(cause, set())
                    changed |= len(found[topic]) > before
    return found


def _joins(profile: Profile) -> tuple[dict[str, dict[str, frozenset[str]]], dict[tuple[str, str], set[str]]]:
    """The nodes that join inputs: per node and output, the inputs it waits for; and the sources a join keys on.

    A node whose output follows one input (once per message of it) while it also takes other inputs of
    that rate, from the same sources, is taken to wait for all of them (a join by frame or stamp, as
    ``message_filters`` and take loops over several topics do): which one it handles last, and so seems
    to cause the output, depends on the mapping, not on the code.
    """
    sources = _upstream_sources(profile)
    joins: dict[str, dict[str, frozenset[str]]] = {}
    keys: dict[tuple[str, str], set[str]] = {}
    for node, spec in profile.nodes.items():
        for cause, outputs in spec.triggers.items():
            if not cause or cause not in profile.topics:
                continue
            rate = profile.topics[cause].rate_hz
            for topic, per in outputs.items():
                if abs(per - 1.0) > JOIN_RATE_TOLERANCE or rate <= 0:
                    continue
                partners = {t for t in spec.handling if t != cause and t in profile.topics
                            and abs(profile.topics[t].rate_hz - rate) <= JOIN_RATE_TOLERANCE * rate
                            and sources.get(t, set()) & sources.get(cause, set())}
                if partners:
                    joins.setdefault(node, {})[topic] = frozenset({cause, *partners})
                    keys[(node, topic)] = set(sources.get(cause, set()))
    return joins, keys


def _hops(trace: tuple[Any, ...] | None, latency: float) -> list[Hop]:
    """The hops of a trace, oldest first, in ms from the chain's first publish."""
    hops = []
    while trace is not None:
        trace, (node, where, arrived, started, ended) = trace
        hops.append(Hop(node, where, arrived, started, ended))
    hops.reverse()
    if hops:
        start = hops[-1].ended - latency if latency else hops[0].arrived
        hops = [Hop(h.node, h.where, h.arrived - start, h.started - start, h.ended - start) for h in hops]
    return hops


def _source_rate(spec: NodeProfile) -> float:
    """How often a source node works (its fastest topic's rate), 0 for a node that only reacts."""
    return max(spec.triggers.get("", {}).values(), default=0.0)


def _source_work(spec: NodeProfile, window_s: float) -> float:
    """A source's CPU per period (ms): its thread's CPU beyond what its callbacks took."""
    rate = _source_rate(spec)
    if rate <= 0:
        return 0.0
    reacting = sum(h.mean_ms / 1000.0 * h.count / window_s for h in spec.handling.values()) if window_s else 0.0
    return max(0.0, spec.cpu_share - reacting) / rate * 1000.0


def predict(profile: Profile, calibration: Calibration, mapping: Mapping, chains: list[Chain], cores: int,
            *, seed: int = 1) -> Prediction:
    return Simulation(profile, calibration, mapping, chains, cores, seed=seed).run()


def fitted(profile: Profile, calibration: Calibration, mapping: Mapping, chains: list[Chain],
           cores: int, *, one_core: Mapping | None = None) -> tuple[Calibration, str]:
    """``calibration`` with its wake scales fitted on the profile's chains, and in words how.

    First the warm scale, on the one-core launch's chains (every node in one process on one core: its
    hops are all warm), then the scale of every other hop, on the chains of the mapping profiled with
    the warm one fixed: ball on plate's chain in one process on one core measured 0.49 ms where the
    calibrated in-process wake (a subscriber asleep a whole period) predicted 0.7. ``one_core`` is the
    one-core launch's mapping (by default every node of the profile in it)."""
    if one_core is None:
        one_core = one_core_mapping(mapping, profile.nodes)
    warm = _scale(profile.one_core_chains, profile, calibration, one_core, chains, cores, "warm_scale")
    if warm is not None:
        calibration = replace(calibration, warm_scale=warm)
    # without a one-core launch every hop shares one scale, fitted on the mapping profiled
    cold = _scale(profile.chains, profile, calibration, mapping, chains, cores,
                  "wake_scale" if warm is not None else "both")
    calibration = replace(calibration, wake_scale=1.0 if cold is None else cold)
    if warm is None:
        calibration = replace(calibration, warm_scale=calibration.wake_scale)
    how = "as calibrated" if cold is None else f"{cold:.2f} of the calibrated, as the profiled chains show"
    if warm is not None:
        how += f"; within a process on one core {warm:.2f}, as the one-core launch's chains show"
    return calibration, how


def one_core_mapping(profiled: Mapping, moved: Iterable[str]) -> Mapping:
    """The mapping of the profile's one-core launch: the nodes it ``moved`` (those of this machine's
    processes and threads) in one process on one core, the others (ROS 1, other machines) where they were."""
    together = Placement("advise_one_core", (0,))
    return {**profiled, **dict.fromkeys(moved, together)}


def _scale(chains_measured: dict[str, dict[str, Any]], profile: Profile, calibration: Calibration, mapping: Mapping,
           chains: list[Chain], cores: int, which: str) -> float | None:
    """How much of the calibrated wakes (those ``which`` scales: ``warm_scale``, ``wake_scale`` or both) the
    measured chains show, or None where none was measured.

    The calibration wakes a subscriber that slept a whole period; along a chain the next node is
    often still warm from its last message, or shares the core's cache, and pays less. The chains
    measured while profiling tell how much: their measured p50 less the model's prediction of that
    very mapping without those wakes, over what the calibrated wakes add to it (0 to 2, averaged over
    the chains). The ratio between a wake in a process and one across processes stays the calibration's.
    """
    measured = {name: float(figures["p50_ms"]) for name, figures in chains_measured.items()}
    if not any(c.name in measured for c in chains):
        return None

    def scaled(value: float) -> Calibration:
        if which == "both":
            return replace(calibration, wake_scale=value, warm_scale=value)
        return replace(calibration, warm_scale=value) if which == "warm_scale" else \
            replace(calibration, wake_scale=value)

    bare = predict(profile, scaled(0.0), mapping, chains, cores)
    full = predict(profile, scaled(1.0), mapping, chains, cores)
    scales = []
    for chain in chains:
        if chain.name not in measured:
            continue
        added = full.chains[chain.name].p50_ms - bare.chains[chain.name].p50_ms
        if added > 0:
            scales.append((measured[chain.name] - bare.chains[chain.name].p50_ms) / added)
    return min(2.0, max(0.0, float(np.mean(scales)))) if scales else None
