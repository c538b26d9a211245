"""The search: the mappings worth simulating, and their ranking.

A candidate puts each movable node on one of the cores (the nodes of one core share a process:
threads of one process take turns anyway, and sharing it spares them a shared-memory hop) or,
where the node has a ``hw:`` implementation and an fpga target is allowed, in hardware. Where
the candidates are few (cores interchangeable, so each grouping of nodes is counted once) all are
simulated; beyond that a mixed-integer program (HiGHS) proposes the best few by a linear
estimate of the model (work on the chains, hops between processes, the most loaded core, what
shares a core with a chain's node at the same time, the fpga part's budget), each then simulated.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from .._errors import AdviseError
from ._calibrate import Calibration
from ._chains import Chain
from ._model import Mapping, Placement, Prediction, predict
from ._profile import Profile

EXHAUSTIVE_LIMIT = 3000
RESOURCES = ("lut", "ff", "bram", "dsp")


@dataclass(frozen=True)
class Limits:
    """What a mapping may use: ``cores`` (0 .. cores-1), an fpga target (its name, and its part's
    budget per resource), the nodes that stay where the project puts them."""

    cores: int
    fpga_target: str = ""
    fpga_budget: dict[str, int] = field(default_factory=dict)
    pinned: frozenset[str] = frozenset()


@dataclass
class Candidate:
    mapping: Mapping
    prediction: Prediction
    label: str = ""

    def worst(self, chains: list[Chain]) -> float:
        """The worst chain's p99 over its deadline (or its p99 in ms where it has none): the ranking key. A
        deadline is a worst case, so it is judged on the tail, not the median."""
        found = 0.0
        for chain in chains:
            p99 = self.prediction.chains[chain.name].p99_ms
            found = max(found, p99 / chain.deadline_ms if chain.deadline_ms else p99)
        return found

    def meets(self, chains: list[Chain]) -> bool:
        return all(self.prediction.chains[c.name].p99_ms <= c.deadline_ms for c in chains if c.deadline_ms)

    def cores_used(self) -> int:
        return len({c for p in self.mapping.values() if not p.fpga for c in p.cpus} or {0})

    def fpga_share(self, budget: dict[str, int], profile: Profile) -> float:
        """The largest share of the part's budget its hardware nodes take (0 without any)."""
        share = 0.0
        for resource, total in budget.items():
            used = sum(profile.nodes[n].hardware.get("resources", {}).get(resource, 0)
                       for n, p in self.mapping.items() if p.fpga)
            share = max(share, used / total if total else 0.0)
        return share


def core_process(core: int) -> str:
    return f"core{core}"


def choices(profile: Profile, original: Mapping, limits: Limits) -> dict[str, list[Placement]]:
    """Per node the placements a candidate may give it."""
    found = {}
    for node in original:
        if node in limits.pinned:
            found[node] = [original[node]]
            continue
        options = [Placement(core_process(c), (c,)) for c in range(limits.cores)]
        hardware = profile.nodes[node].hardware if node in profile.nodes else {}
        if limits.fpga_target and hardware.get("ms") is not None:
            options.append(Placement(limits.fpga_target, (), fpga=True))
        found[node] = options
    return found


def _groupings(nodes: list[str], cores: int) -> Iterator[dict[str, int]]:
    """Each way to put ``nodes`` on up to ``cores`` interchangeable cores, once (restricted growth)."""
    def grow(at: int, used: int, chosen: dict[str, int]) -> Iterator[dict[str, int]]:
        if at == len(nodes):
            yield dict(chosen)
            return
        for core in range(min(used + 1, cores)):
            chosen[nodes[at]] = core
            yield from grow(at + 1, max(used, core + 1), chosen)
        del chosen[nodes[at]]
    yield from grow(0, 0, {})


def _count(options: dict[str, list[Placement]], symmetric: bool, cores: int) -> int:
    if not symmetric:
        total = 1
        for placed in options.values():
            total *= len(placed)
        return total
    movable = [n for n, o in options.items() if len(o) > 1]
    hardware = [n for n in movable if any(p.fpga for p in options[n])]
    partitions = [[1] + [0] * cores]  # Stirling numbers: ways to group k nodes into j cores
    for _k in range(len(movable)):
        row = [0] * (cores + 1)
        for j in range(1, cores + 1):
            row[j] = j * partitions[-1][j] + partitions[-1][j - 1]
        partitions.append(row)
    return sum(partitions[-1]) << len(hardware)


def exhaustive(options: dict[str, list[Placement]], cores: int) -> Iterator[Mapping]:
    """Every candidate, cores counted once each when no node is pinned to a particular core."""
    fixed = {n: o[0] for n, o in options.items() if len(o) == 1}
    movable = [n for n, o in options.items() if len(o) > 1]
    symmetric = not any(p.cpus for p in fixed.values())
    if not symmetric:
        for picked in itertools.product(*(options[n] for n in movable)):
            yield {**fixed, **dict(zip(movable, picked, strict=True))}
        return
    hardware = [n for n in movable if any(p.fpga for p in options[n])]
    for in_fpga in itertools.chain.from_iterable(itertools.combinations(hardware, k) for k in range(len(hardware) + 1)):
        software = [n for n in movable if n not in in_fpga]
        fpga = {n: next(p for p in options[n] if p.fpga) for n in in_fpga}
        for grouping in _groupings(software, cores):
            yield {**fixed, **fpga, **{n: Placement(core_process(c), (c,)) for n, c in grouping.items()}}


def _demand_ms(profile: Profile, node: str) -> float:
    """A node's CPU per second (ms), from its profile: what it adds to a core's load."""
    spec = profile.nodes[node]
    return spec.cpu_share * 1000.0


def proposed(profile: Profile, calibration: Calibration, options: dict[str, list[Placement]],
             chains: list[tuple[Chain, list[str]]], cores: int, count: int, time_limit_s: float) -> list[Mapping]:
    """The best ``count`` candidates by the linear estimate, from HiGHS (each solve bounded in time)."""
    import highspy

    solver: Any = highspy.Highs()  # type: ignore[no-untyped-call]
    solver.setOptionValue("output_flag", False)
    solver.setOptionValue("time_limit", max(1.0, time_limit_s / max(count, 1)))
    nodes = list(options)
    pick: dict[tuple[str, int], Any] = {(n, k): solver.addBinary() for n in nodes for k in range(len(options[n]))}
    for n in nodes:
        solver.addConstr(sum(pick[n, k] for k in range(len(options[n]))) == 1)
    on_core: dict[tuple[str, int], list[Any]] = {}
    for n in nodes:
        for k, placement in enumerate(options[n]):
            for core in placement.cpus if not placement.fpga else ():
                on_core.setdefault((n, core), []).append(pick[n, k])
    peak = solver.addVariable(lb=0.0)
    for core in range(cores):
        load = sum(_demand_ms(profile, n) * v for n in nodes for v in on_core.get((n, core), []))
        solver.addConstr(peak >= load)
        solver.addConstr(load <= 950.0)  # a core can give at most 95 % of each second
    objective: Any = 0.01 * peak
    for chain, path in chains:
        weight = 1.0 / (chain.deadline_ms or 1.0)
        for node in path:
            for k, placement in enumerate(options[node]):
                work = profile.nodes[node].hardware.get("ms", 0.0) if placement.fpga else \
                    _mean_ms(profile, node)
                objective = objective + weight * work * pick[node, k]
        for sender, receiver, topic in _edges(profile, path):
            size = profile.topics[topic].size_bytes
            hop = calibration.hop_ms("shm", size) - calibration.hop_ms("inproc", size) + 0.01
            for core in range(cores):
                apart = solver.addVariable(lb=0.0)
                solver.addConstr(apart >= sum(on_core.get((sender, core), [])) - sum(on_core.get((receiver, core), [])))
                objective = objective + weight * hop * apart
        for node in path:  # what runs beside a chain's node on its core delays it
            for other in nodes:
                if other == node or other in path:
                    continue
                for core in range(cores):
                    together = solver.addVariable(lb=0.0)
                    solver.addConstr(together >= sum(on_core.get((node, core), []))
                                     + sum(on_core.get((other, core), [])) - 1)
                    objective = objective + weight * 0.5 * _mean_ms(profile, other) * together
    solver.minimize(objective)
    found: list[Mapping] = []
    deadline = time.monotonic() + time_limit_s
    while len(found) < count and time.monotonic() < deadline:
        solver.run()
        if solver.getModelStatus() not in (highspy.HighsModelStatus.kOptimal, highspy.HighsModelStatus.kTimeLimit):
            break
        values = solver.getSolution().col_value
        chosen = {n: k for n in nodes for k in range(len(options[n])) if values[pick[n, k].index] > 0.5}
        if len(chosen) != len(nodes):
            break
        found.append({n: options[n][k] for n, k in chosen.items()})
        solver.addConstr(sum(pick[n, k] for n, k in chosen.items()) <= len(nodes) - 1)  # not this one again
    if not found:
        raise AdviseError("the solver found no mapping within the limits: the nodes' CPU needs more cores than "
                          "given (--cores), or the fpga part's budget is too small")
    return found


def _edges(profile: Profile, nodes: list[str]) -> list[tuple[str, str, str]]:
    """(publisher, subscriber, topic) of each topic between two of ``nodes`` that the subscriber handled."""
    return [(sender, receiver, topic) for receiver in nodes if receiver in profile.nodes
            for topic in profile.nodes[receiver].handling if topic in profile.topics
            for sender in profile.topics[topic].publishers if sender in nodes]


def _mean_ms(profile: Profile, node: str) -> float:
    handling = profile.nodes[node].handling
    return max((h.mean_ms for h in handling.values()), default=0.0)


def search(profile: Profile, calibration: Calibration, original: Mapping, chains: list[tuple[Chain, list[str]]],
           limits: Limits, *, keep: int = 5, time_limit_s: float = 60.0) -> tuple[list[Candidate], str]:
    """The candidates, simulated and ranked (deadlines met first, then the worst chain's latency, then
    fewer nodes moved, fewer cores and less fpga); and how they were found."""
    options = choices(profile, original, limits)
    symmetric = not any(o[0].cpus for o in options.values() if len(o) == 1)
    total = _count(options, symmetric, limits.cores)
    plain = [c for c, _ in chains]
    if total <= EXHAUSTIVE_LIMIT:
        mappings = list(exhaustive(options, limits.cores))
        how = f"all {len(mappings)} candidates simulated"
    else:
        mappings = proposed(profile, calibration, options, chains, limits.cores, max(keep * 4, 20), time_limit_s)
        how = (f"{total} candidates are too many to simulate: HiGHS proposed {len(mappings)} by a linear estimate, "
               "each simulated")
    if original not in mappings:  # the project's own mapping competes too: where nothing beats it, it stays
        mappings.append(original)
    scored = [Candidate(m, predict(profile, calibration, m, plain, limits.cores)) for m in mappings]
    scored = [c for c in scored if not _over_budget(c, limits, profile)]
    given = next(c for c in scored if c.mapping == original).worst(plain)
    scored.sort(key=lambda c: (not c.meets(plain), _latency_key(c.worst(plain), given), _moves(c.mapping, original),
                               c.cores_used(), c.fpga_share(limits.fpga_budget, profile)))
    return scored[:keep], how


WORTH_MOVING = 0.03


def _latency_key(worst: float, given: float) -> float:
    """The ranking's latency key: a candidate within ``WORTH_MOVING`` (3 %) of the project's own mapping
    ranks as that mapping does, so that a gain smaller than what runs differ by never buys a change
    (fewer nodes moved decide); beyond it, the worst chain in steps of 1 %."""
    if abs(worst - given) <= WORTH_MOVING * given:
        return round(given * 100, 6)
    return float(round(worst * 100))


def _moves(mapping: Mapping, original: Mapping) -> int:
    """How many nodes a candidate puts somewhere else than the project (one process's nodes regrouped on
    the same cores count as unmoved)."""
    groups: dict[Placement, frozenset[str]] = {}
    for placement in set(original.values()):
        groups[placement] = frozenset(n for n, p in original.items() if p == placement)
    moved = 0
    for node, placement in mapping.items():
        same = frozenset(n for n, p in mapping.items() if p == placement)
        before = original[node]
        if placement != before and not (same == groups[before] and placement.cpus == before.cpus
                                         and placement.fpga == before.fpga):
            moved += 1
    return moved


def _over_budget(candidate: Candidate, limits: Limits, profile: Profile) -> bool:
    return bool(limits.fpga_budget) and candidate.fpga_share(limits.fpga_budget, profile) > 1.0
