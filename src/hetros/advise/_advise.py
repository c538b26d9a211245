"""``hetros advise``: profile (or read a profile), calibrate, search, tell, write, verify."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .._errors import AdviseError
from ..plan import Plan
from ._calibrate import Calibration, calibration
from ._chains import Chain, ChainLatency, HardwareSpan, cosimulated_latency, over_launches
from ._hardware import fpga_target, hardware_nodes, hardware_profile, part_budget
from ._measure import BUSY_LIMIT, busy_share
from ._model import Mapping, Placement, fitted, one_core_mapping, predict
from ._observe import Observation, observe
from ._profile import Profile, build, chain_latencies, graph_key, pooled, with_one_core
from ._report import joins_one_core, plot_timeline, table, write_one_core, write_project
from ._search import Candidate, Limits, search


@dataclass
class Options:
    chains: list[Chain]
    out: Path
    profile: Path | None = None  # read this profile instead of running the project
    duration: float = 20.0
    warmup: float = 5.0
    cores: int = 0  # 0: the cores this process may use
    pinned: frozenset[str] = frozenset()
    fpga: bool = False  # candidates may put nodes with ``hw:`` into the project's fpga target
    keep: int = 3
    calibration: Path | None = None
    recalibrate: bool = False
    time_limit_s: float = 60.0
    rounds: int = 1  # the profile's launches, and --verify's of each mapping (interleaved)
    busy_ok: bool = False  # measure even on a busy machine, and reuse a cached calibration unchecked


@dataclass
class Advice:
    profile: Profile
    calibrated: str
    original: Candidate
    ranked: list[Candidate]
    how: str
    paths: list[tuple[Chain, list[str]]]
    limits: Limits
    targets: dict[str, str]

    def table(self) -> str:
        rows = [(f"#{i}", c) for i, c in enumerate(self.ranked, 1)] + [("as given", self.original)]
        return table(rows, [c for c, _ in self.paths], self.original.mapping, self.targets, self.limits, self.profile)

    def shortfall(self) -> str:
        """Why no mapping meets the deadlines: by how much the best misses, and what dominates; "" when one does."""
        chains = [c for c, _ in self.paths]
        best = self.ranked[0]
        if best.meets(chains):
            return ""
        misses = []
        for chain in chains:
            prediction = best.prediction.chains[chain.name]
            if chain.deadline_ms and prediction.p99_ms > chain.deadline_ms:
                node = prediction.dominant()
                misses.append(f"chain {chain.name}: the best mapping's p99 is {prediction.p99_ms:.1f} ms, "
                              f"{prediction.p99_ms - chain.deadline_ms:.1f} ms over its {chain.deadline_ms:g} ms "
                              f"deadline; {node} dominates ({prediction.working_ms.get(node, 0.0):.1f} ms working, "
                              f"{prediction.waiting_ms.get(node, 0.0):.1f} ms waiting)")
        return "no mapping within the limits meets the deadline: " + "; ".join(misses) + \
            ". Allow more cores (--cores), hardware (--fpga, for nodes with hw:), or make that node faster"


def mapping_of(plan: Plan) -> tuple[Mapping, dict[str, str]]:
    """Each node's placement in ``plan``, and its target's name."""
    found, targets = {}, {}
    for node, spec in plan.nodes.items():
        if spec.run.startswith("hetros."):
            continue
        target = plan.targets[spec.target]
        found[node] = Placement(target.name if target.kind == "fpga" else plan.process_of(node), tuple(target.cpus),
                                fpga=target.kind == "fpga")
        targets[node] = spec.target
    return found, targets


SOFTWARE_TARGET = "advise_software"


def profile_project(project: Path, plan: Plan, options: Options) -> Profile:
    """Run the project and keep what the model needs (``<out>/profile.json``): as it is mapped, except
    that nodes in hardware run their software (``run:``) in a process of their own, so that both of
    their figures are known; those with ``hw:`` are then co-simulated on the inputs they met.

    Then as many launches with every node in one process pinned to one core: a node that runs right after
    its publisher, on the same awake core, runs faster than one whose core it wakes from idle (ball on
    plate's control 221 against 284 µs a message, its touch 60 against 121), and the mappings that put a
    chain in one process measured up to 1.4x faster than the model said without it."""
    for chain in options.chains:
        chain.check(plan)
    capable = hardware_nodes(plan) if fpga_target(plan) else []
    in_hardware = [n for n in plan.nodes if plan.in_hardware(n)]
    samples = frozenset(t for n in capable for t in plan.nodes[n].subscribe)
    original, targets = mapping_of(plan)
    run, removed = project, []
    if in_hardware:
        software = {n: Placement(SOFTWARE_TARGET) if n in in_hardware else p for n, p in original.items()}
        run = write_project(project, software, original, targets, project.with_name(f".{project.stem}_software.yaml"))
        removed.append(run)
    cpu = min(os.sched_getaffinity(0))
    placed = {(p.process, p.cpus) for n, p in original.items() if not p.fpga and n not in in_hardware}
    one_core_launch = len(placed) > 1 or any(len(cpus) != 1 for _, cpus in placed)
    try:
        from ..project import plan_file

        launches, one_core = [], []
        for round_ in range(options.rounds):
            log = options.out / ("profile-launch.log" if round_ == 0 else f"profile-launch-{round_ + 1}.log")
            launches.append(observe(run, plan_file(run), duration=options.duration, warmup=options.warmup,
                                    profiling=True, log=log, samples=samples))
        if one_core_launch:
            pinned = write_one_core(run, cpu, project.with_name(f".{project.stem}_one_core.yaml"))
            removed.append(pinned)
            for round_ in range(options.rounds):
                log = options.out / f"profile-one-core-{round_ + 1}.log"
                one_core.append(observe(pinned, plan_file(pinned), duration=options.duration,
                                        warmup=options.warmup, profiling=True, log=log))
    finally:
        for path in removed:
            path.unlink(missing_ok=True)
    seen = launches[-1]
    profile = pooled([build(launch, options.chains) for launch in launches], launches, options.chains)
    with_one_core(profile, pooled([build(launch, options.chains) for launch in one_core], one_core, options.chains)
                  if one_core else profile)
    profile.graph = graph_key(plan)
    hardware_profile(plan, project, profile, seen)
    profile.save(options.out / "profile.json")
    return profile


def refuse_busy(options: Options) -> None:
    """An advice measured while other processes keep the machine busy carries their load, and would not hold
    on the quiet machine it is for: refused (AdviseError), unless ``--busy-ok`` says to measure anyway."""
    if options.busy_ok:
        return
    busy = busy_share(1.0)
    if busy > BUSY_LIMIT:
        raise AdviseError(f"the machine is busy: {busy:.0%} of its CPU time went to other processes over the last "
                          f"second (more than {BUSY_LIMIT:.0%}); a profile measured now would carry their load and "
                          "the advice would not hold on a quiet machine. Advise when it is quiet, or pass --busy-ok "
                          "to measure anyway (the figures then describe this load)")


def advise(project: Path, plan: Plan, options: Options, warn: Callable[[str], None] = lambda _: None) -> Advice:
    """The best mappings of ``project`` for ``options.chains``; ``warn`` hears what does not stop the advice
    (a profile taken of another graph or on another machine) as soon as it is known."""
    paths = [(c, c.check(plan)) for c in options.chains]
    if not paths:
        raise AdviseError("name at least one chain: --chain /first_topic:/last_topic[@DEADLINEms], or chains: in "
                          "the project file")
    if options.profile is not None:
        profile = Profile.load(options.profile)
        for warning in profile.fits(plan):
            warn(warning)
    else:
        refuse_busy(options)
        profile = profile_project(project, plan, options)
    if options.calibration is not None:
        calibrated, source = Calibration.load(options.calibration), f"calibration {options.calibration}"
    else:
        calibrated, source = calibration(again=options.recalibrate, check=not options.busy_ok)
    original, targets = mapping_of(plan)
    unknown = sorted(set(original) - set(profile.nodes))
    if unknown:
        raise AdviseError(f"the profile has no figures of node(s) {', '.join(unknown)}: they did not run while it "
                          "was taken (or it is another project's); profile again")
    cores = options.cores or len(os.sched_getaffinity(0))
    fpga = fpga_target(plan) if options.fpga else ""
    if options.fpga and not fpga:
        raise AdviseError("--fpga needs an fpga target in the project (targets: {name: {kind: fpga, ...}}) to put "
                          "hardware nodes into, and nodes with hw: implementations")
    limits = Limits(cores, fpga, part_budget(plan, fpga) if fpga else {}, options.pinned)
    chains = [c for c, _ in paths]
    profiled = _profiled_mapping(profile, original)
    calibrated, fit = fitted(profile, calibrated, profiled, chains, cores,
                             one_core=one_core_mapping(profiled, _one_core_nodes(plan)))
    shipped = Candidate(original, predict(profile, calibrated, original, chains, cores))
    ranked, how = search(profile, calibrated, original, paths, limits, keep=options.keep,
                         time_limit_s=options.time_limit_s)
    wake = calibrated.wake_ms
    how += (f"; waking a subscriber adds {wake.get('inproc', 0.0) * calibrated.wake_scale * 1000:.0f} µs in a "
            f"process ({wake.get('inproc', 0.0) * calibrated.warm_scale * 1000:.0f} µs in one on one core), "
            f"{wake.get('shm', 0.0) * calibrated.wake_scale * 1000:.0f} µs across processes "
            f"({wake.get('shm_one_core', 0.0) * calibrated.wake_scale * 1000:.0f} µs pinned to one core; {fit})")
    if any(spec.one_core for spec in profile.nodes.values()):
        how += ("; a node whose publisher is in its process, pinned to one core, works at its time in the one-core "
                "launch")
    return Advice(profile, source, shipped, ranked, how, paths, limits, targets)


def _one_core_nodes(plan: Plan) -> list[str]:
    """The nodes the profile's one-core launch runs together (``write_one_core``): those of this machine's
    processes and threads, and those mapped to hardware (which the profile runs in software)."""
    return [node for node, spec in plan.nodes.items() if not spec.run.startswith("hetros.") and (
        plan.in_hardware(node) or joins_one_core(plan.targets[spec.target].kind, plan.targets[spec.target].host))]


def _profiled_mapping(profile: Profile, original: Mapping) -> Mapping:
    """The mapping the profile was measured in: each node's process and cpus as the profile recorded them
    (the project's own, except that nodes it maps to hardware ran their software in a process)."""
    return {n: Placement(profile.nodes[n].process, tuple(profile.nodes[n].cpus)) if n in profile.nodes else p
            for n, p in original.items()}


def write(project: Path, advice: Advice, out: Path) -> tuple[Path, Path]:
    """The best mapping as a project file beside ``project`` and its predicted timeline (a PNG in ``out``)."""
    written = write_project(project, advice.ranked[0].mapping, advice.original.mapping, advice.targets,
                            project.with_name(f"{project.stem}_advised.yaml"))
    picture = plot_timeline(advice.ranked[0], [c for c, _ in advice.paths], out / "timeline.png")
    return written, picture


def verify(projects: dict[str, Path], plans: dict[str, Plan], chains: list[Chain], options: Options
           ) -> dict[str, dict[str, ChainLatency | None]]:
    """Launch each project (not profiling) and measure its chains: in wall time, except that a chain through
    an fpga target is measured with its hardware in co-simulated time (``cosimulated_latency``), since a
    co-simulation is slower than the hardware it stands for."""
    rounds: dict[str, list[dict[str, ChainLatency | None]]] = {label: [] for label in projects}
    for round_ in range(max(1, options.rounds)):
        # interleaved (every mapping once, then again), so a drift of the machine's load meets each of them
        for label, project in projects.items():
            plan = plans[label]
            suffix = f"-{round_ + 1}" if options.rounds > 1 else ""
            seen = observe(project, plan, duration=options.duration, warmup=options.warmup, profiling=False,
                           log=options.out / f"verify-{label.strip('#').replace(' ', '-')}{suffix}.log")
            measured = chain_latencies(seen, chains)
            if any(plan.in_hardware(n) for n in plan.nodes):
                hop = _shm_hop(calibration()[0])
                spans = hardware_spans(seen)
                for chain in chains:
                    if any(plan.in_hardware(n) for n in chain.check(plan)):
                        measured[chain.name] = cosimulated_latency(plan, chain, seen.published, spans, hop)
            rounds[label].append(measured)
    return {label: {chain.name: over_launches([r[chain.name] for r in launches]) for chain in chains}
            for label, launches in rounds.items()}


def _shm_hop(costs: Calibration) -> Callable[[str, int], float]:
    """A shared-memory hop to a sleeping subscriber (the gateway), in ns, as the model costs it."""
    return lambda _topic, size: costs.hop_ms("shm", size) * 1e6


def hardware_spans(seen: Observation) -> dict[tuple[str, int], HardwareSpan]:
    """Each gateway's co-simulated spans, by (output topic, stamp), from the figures read at the run's end."""
    spans: dict[tuple[str, int], HardwareSpan] = {}
    for process in seen.late.values():
        for figures in (node.get("figures", {}) for node in process.get("nodes", {}).values()):
            for span in figures.get("spans", ()):
                spans[(str(span["topic"]), int(span["stamp"]))] = HardwareSpan(float(span["sim_ns"]),
                                                                               float(span["cpu_ns"]))
    return spans
