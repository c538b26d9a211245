"""``hetros advise``: the mapping that meets a chain's deadline, predicted and (``--verify``) measured."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING

from .._errors import AdviseError
from ._args import count, positive_count, positive_seconds, seconds

if TYPE_CHECKING:
    from ..advise import Advice, Options

EXIT_MISSED = 1


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("advise", help="the mapping that meets a chain's deadline: profile, model, search, write, "
                                      "verify")
    p.add_argument("project")
    p.add_argument("--chain", action="append", default=[], metavar="[NAME=]/FIRST:/LAST[@MSms]",
                   help="a chain to optimise: first topic, last topic, optional deadline (repeatable; adds to, or "
                        "by name replaces, the project's chains:)")
    p.add_argument("--profile", metavar="PROFILE.json",
                   help="advise from this profile instead of running the project (see --profile-only)")
    p.add_argument("--profile-only", action="store_true", help="run the project, write OUT/profile.json, stop there")
    p.add_argument("--duration", type=seconds, default=20.0, help="seconds each run lasts (default 20)")
    p.add_argument("--warmup", type=seconds, default=5.0, help="seconds of each run not counted (default 5)")
    p.add_argument("--cores", type=count, default=0, help="cores a mapping may use (default: this machine's)")
    p.add_argument("--pin", action="append", default=[], metavar="NODE",
                   help="a node that stays where the project puts it (repeatable)")
    p.add_argument("--fpga", action="store_true",
                   help="nodes with a hw: implementation may go into the project's fpga target")
    p.add_argument("--top", type=positive_count, default=3, help="how many mappings to show (default 3)")
    p.add_argument("--calibration", metavar="FILE", help="transport costs from this file instead of this machine's")
    p.add_argument("--calibrate", action="store_true", help="measure this machine's transport costs again")
    p.add_argument("--busy-ok", action="store_true",
                   help="profile and calibrate even while other processes keep the machine busy (refused by "
                        "default: the figures would carry their load), and reuse a cached calibration unchecked")
    p.add_argument("--time-limit", type=positive_seconds, default=60.0, help="seconds the solver may take (default 60)")
    p.add_argument("--out", default="out/advise", help="folder for the profile, the timeline and logs")
    p.add_argument("--verify", action="store_true",
                   help="launch the advised mapping and the project's own, and print predicted beside measured")
    p.add_argument("--rounds", type=positive_count, default=1,
                   help="profile over this many launches (node times pooled, the chains' median p50) and, with "
                        "--verify, launch each mapping this many times, interleaved, taking the median of their "
                        "chain p50s (a chain under a millisecond varies from launch to launch)")
    p.set_defaults(func=cmd_advise)


def cmd_advise(args: argparse.Namespace) -> int:
    # imported here: every `hetros` command builds this parser, and the advisor and the project checks
    # cost a command that does not use them 0.15 s
    from ..advise import Chain, Options, advise, profile_project, refuse_busy, write
    from ..project import load_project, plan_file

    project = Path(args.project)
    plan = plan_file(project)
    if args.cores < 0:
        raise AdviseError(f"--cores must be a positive number of cores, not {args.cores}")
    if args.rounds < 1:
        raise AdviseError(f"--rounds must be at least 1, not {args.rounds}")
    unknown = sorted(set(args.pin) - set(plan.nodes))
    if unknown:
        raise AdviseError(f"--pin names no node of the project: {', '.join(unknown)} (its nodes: "
                          f"{', '.join(sorted(plan.nodes))})")
    chains = {name: Chain(name, spec.first, spec.last, spec.deadline_ms)
              for name, spec in load_project(project).model.chains.items()}
    chains.update((chain.name, chain) for chain in (Chain.parse(text) for text in args.chain))
    options = Options(list(chains.values()), Path(args.out),
                      Path(args.profile) if args.profile else None, args.duration, args.warmup, args.cores,
                      frozenset(args.pin), args.fpga, max(1, args.top),
                      Path(args.calibration) if args.calibration else None, args.calibrate, args.time_limit,
                      args.rounds, args.busy_ok)
    options.out.mkdir(parents=True, exist_ok=True)
    if args.profile_only:
        for chain in options.chains:
            chain.check(plan)
        refuse_busy(options)
        profile_project(project, plan, options)
        print(f"wrote {options.out / 'profile.json'}")
        return 0
    advice = advise(project, plan, options, warn=lambda text: print(f"warning: {text}", flush=True))
    where = f"read from {options.profile}" if options.profile else f"measured now, {options.out / 'profile.json'}"
    print(f"profile: {where}; transport costs: {advice.calibrated}; {advice.how}\n")
    print(advice.table())
    written, picture = write(project, advice, options.out)
    print(f"\nwrote {written} (the best mapping; only targets and cpus differ) and {picture}")
    shown = [*[(f"#{rank}", c) for rank, c in enumerate(advice.ranked, 1)], ("as given", advice.original)]
    summary: dict[str, object] = {"predicted": {label: {c.name: candidate.prediction.chains[c.name].p50_ms
                                                        for c, _ in advice.paths} for label, candidate in shown}}
    code = 0
    shortfall = advice.shortfall()
    if shortfall:
        print(f"\nerror: {shortfall}")
        code = EXIT_MISSED
    if args.verify:
        summary["measured"], launches = _verify(project, written, advice, options)
        if options.rounds > 1:
            summary["launch_p50s"] = launches
    (options.out / "advice.json").write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
    return code


def _verify(project: Path, written: Path, advice: Advice, options: Options
            ) -> tuple[dict[str, dict[str, float]], dict[str, dict[str, list[float]]]]:
    from ..advise import verify, write_project
    from ..project import plan_file

    """Launch the shown mappings (the best as written, the others from hidden sibling files removed after)
    and the project's own; print each chain's predicted beside its measured latency."""
    chains = [c for c, _ in advice.paths]
    projects = {"#1": written}
    extra = []
    for rank, candidate in enumerate(advice.ranked[1:], 2):
        path = project.with_name(f".{project.stem}_advised_{rank}.yaml")
        write_project(project, candidate.mapping, advice.original.mapping, advice.targets, path)
        projects[f"#{rank}"] = path
        extra.append(path)
    projects["as given"] = project
    try:
        measured = verify(projects, {label: plan_file(path) for label, path in projects.items()}, chains, options)
    finally:
        for path in extra:
            path.unlink(missing_ok=True)
    how = f"each launched {options.rounds} times, interleaved, the median of their p50s and p99s; " \
        if options.rounds > 1 else "each launched "
    print(f"\nverified ({how}for {options.duration:g} s, the first {options.warmup:g} s not counted):")
    print(f"{'mapping':<9} {'chain':<16} {'predicted p50/p99 ms':>21} {'measured p50/p99 ms':>20} {'p50 error':>9}")
    found: dict[str, dict[str, float]] = {}
    launches: dict[str, dict[str, list[float]]] = {}
    any_cosimulated = False
    candidates = [*zip(projects, [*advice.ranked, advice.original], strict=True)]
    for label, candidate in candidates:
        for chain in chains:
            predicted = candidate.prediction.chains[chain.name]
            latency = measured[label][chain.name]
            if latency is None:
                print(f"{label:<9} {chain.name:<16} {predicted.p50_ms:>10.1f}/{predicted.p99_ms:<10.1f} "
                      f"{'(no message went through)':>20}")
                continue
            error = (predicted.p50_ms - latency.p50_ms) / latency.p50_ms if latency.p50_ms else 0.0
            cosimulated = "co-simulated" in latency.matched_by
            spread = (f"  (launches: {', '.join(f'{v:.2f}' for v in latency.launch_p50s_ms)})"
                      if latency.launch_p50s_ms else "")
            print(f"{label:<9} {chain.name:<16} {predicted.p50_ms:>10.1f}/{predicted.p99_ms:<10.1f} "
                  f"{latency.p50_ms:>9.1f}/{latency.p99_ms:<10.1f} {error:>+8.0%}" + (" *" if cosimulated else "")
                  + spread)
            found.setdefault(label, {})[chain.name] = latency.p50_ms
            launches.setdefault(label, {})[chain.name] = list(latency.launch_p50s_ms)
            any_cosimulated = any_cosimulated or cosimulated
    if any_cosimulated:
        print("* through an fpga target: its hardware in co-simulated time at the target's clock (the gateway's "
              "cycles and copies), the software as measured")
    return found, launches
