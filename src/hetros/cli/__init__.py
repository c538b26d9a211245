"""The ``hetros`` command line."""

from __future__ import annotations

import argparse
import atexit
import contextlib
import faulthandler
import math
import os
import re
import shlex
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from .._errors import CheckError, Error, HardwareError, ProjectError
from .._files import printable
from .._signals import interruptible
from ..hw import DEFAULT_TRACE_WINDOW as TRACE_WINDOW
from ..msg import registry
from ..msg import wanted as compiled_wanted
from ..plan import Plan
from ._args import microseconds, milliseconds, port, positive_count, seconds

if TYPE_CHECKING:
    from ..project import LoadedProject

EXIT_ERROR = 1
# an exception hetros did not expect: a defect (sysexits' EX_SOFTWARE); the tests fail on it
EXIT_BUG = 70
# where crash reports go instead of the user's private folder (the test suite collects them there)
CRASH_DIR_VARIABLE = "HETROS_CRASH_DIR"


def _write_yaml(data: object, out: str | None, mode: int = 0o666) -> None:
    """``data`` as YAML to ``out`` (else stdout), made with ``mode`` under the user's umask: a project that
    holds a file's text is no more readable than that file."""
    text = yaml.safe_dump(data, sort_keys=False, default_flow_style=False)
    if out:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        descriptor = os.open(out, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, mode)
        os.fchmod(descriptor, os.fstat(descriptor).st_mode & mode & 0o7777)  # an existing file narrows too
        with os.fdopen(descriptor, "w", encoding="utf-8") as written:
            written.write(text)
        print(f"wrote {out}")
    else:
        sys.stdout.write(text)


def cmd_check(args: argparse.Namespace) -> int:
    from ..project import check, load_project

    project = load_project(args.project)
    report = check(project)
    for warning in report.warnings:
        print(f"warning: {warning}")
    if report.errors:
        print(CheckError(report.errors), file=sys.stderr)
        return EXIT_ERROR
    print(f"{args.project}: OK ({len(project.model.nodes)} nodes)")
    if args.resolved:
        print(resolved_graph(project))
    return 0


_SECTIONS = ("publish", "subscribe", "services", "clients", "actions", "action_clients")


def resolved_graph(project: LoadedProject) -> str:
    """Each node as the project resolves it: its target, ROS name, namespace, remaps and final endpoint names."""
    lines = []
    for key, node in project.model.nodes.items():
        ros = f"{node.namespace}/{node.name or key}"
        lines.append(f"{key}  (ROS name {ros}, target {node.target})")
        for section in _SECTIONS:
            for endpoint, entry in getattr(node, section).items():
                typename = entry if isinstance(entry, str) else entry.type
                lines.append(f"  {section:<15} {endpoint}  {typename}")
        for source, target in node.remap.items():
            lines.append(f"  {'remap':<15} {source} -> {target}")
        for name, value in node.parameters.items():
            lines.append(f"  {'parameter':<15} {name} = {value!r}")
    return "\n".join(lines)


def cmd_graph(args: argparse.Namespace) -> int:
    from ..project import describe, plan_file, write_graph

    rates = None
    if args.live:
        from ._inspect import live_rates

        plan, rates = live_rates(args.session, args.project)
    elif args.project:
        plan = plan_file(args.project)
    else:
        raise CheckError(["hetros graph needs a project file, or --live for a running launch"])
    print(describe(plan, rates))
    if args.out:
        for path in write_graph(plan, Path(args.out), rates):
            print(f"wrote {path}")
    return 0


def _hardware_tools() -> None:
    """The fpga commands need the rtl extra (Amaranth, Yosys: about 130 MB, so not in ``make install``)."""
    import importlib.util

    if importlib.util.find_spec("amaranth") is None:
        raise HardwareError("the hardware tools are not installed: run `make install-rtl` "
                            "(or `.venv/bin/pip install -e '.[rtl]'`: Amaranth and Yosys, about 130 MB)")


def cmd_hw_build(args: argparse.Namespace) -> int:
    _hardware_tools()
    from ..hw import build_target

    plan, targets = _fpga_targets(args)
    for target in targets:
        for path in build_target(plan, target, Path(args.output), registry()):
            print(f"wrote {path}")
    return 0


def cmd_hw_export(args: argparse.Namespace) -> int:
    _hardware_tools()
    from ..hw import export

    plan, targets = _fpga_targets(args)
    for target in targets:
        board = args.board or plan.targets[target].board
        if not board:
            raise HardwareError(f"fpga target {target} names no board: give --board zcu104|pynq-z2|ultra96 or "
                                f"board: on the target")
        out = Path(args.output) / target if len(targets) > 1 else Path(args.output)
        for path in export(plan, target, board, out, registry()):
            print(f"wrote {path}")
    return 0


def cmd_hw_bitstream(args: argparse.Namespace) -> int:
    _hardware_tools()
    from ..hw import bitstreams, format_bitstreams

    plan, targets = _fpga_targets(args)
    rows = []
    for target in targets:
        rows += bitstreams(plan, target, Path(args.output) / target, registry(), args.parts)
    print(format_bitstreams(rows))
    print("\n(each design inside a pin harness on a Lattice ECP5: YoWASP's Yosys, nextpnr-ecp5 and ecppack; "
          "Fmax is nextpnr's achieved figure for the worst clock)")
    missed = [row for row in rows if not row.meets_clock]
    for row in missed:  # timing is a check: a design that misses its clock fails the command
        print(f"error: {row.timing_failure()}", file=sys.stderr)
    return EXIT_ERROR if missed else 0


def _fpga_targets(args: argparse.Namespace) -> tuple[Plan, list[str]]:
    from ..project import plan_file

    plan = plan_file(args.project)
    fpga = [t.name for t in plan.targets.values() if t.kind == "fpga"]
    if not fpga:
        raise HardwareError(f"{args.project} has no fpga target: add one (targets: {{fpga0: {{kind: fpga}}}}) and "
                            "put the nodes of a topic on it")
    return plan, [args.target] if args.target else fpga


def cmd_hw_report(args: argparse.Namespace) -> int:
    _hardware_tools()
    from ..hw import format_transfers, transfer_report

    plan, targets = _fpga_targets(args)
    if args.models:
        return _execution_models(args, plan, targets)
    for target in targets:
        print(f"fpga target {target}: one message from the first publisher to every subscriber, simulated "
              "(cycles from the first beat offered to the last TLAST taken)\n")
        print(format_transfers(transfer_report(plan, target, simulator=args.simulator)))
        print(_clock_line(plan, target))
    return 0


def _clock_line(plan: Plan, target: str) -> str:
    """Which clock a target's figures use: its clock_mhz, or the Fmax place and route achieved if lower."""
    from ..hw import target_clock

    clock = target_clock(plan, target)
    return f"\n(times at {clock.mhz:g} MHz: {clock.source})\n"


def _execution_models(args: argparse.Namespace, plan: Plan, targets: list[str]) -> int:
    """``hw report --models``: each target's hardware nodes as a dataflow chain and as a sequential one."""
    from ..hw import channels_of, execution_models, format_models, hardware_topics, sample_message
    from ..plan import gateway_node

    width, _, height = args.image.partition("x")
    if not (width.isdigit() and height.isdigit()):
        raise HardwareError(f"--image must be WIDTHxHEIGHT (640x480), not {args.image!r}")
    types = registry()
    for folder in plan.message_paths:
        types.load_folder(Path(folder))
    for target in targets:
        gateway = gateway_node(target)
        inputs = {t.name: t.type for t in hardware_topics(plan, target) if gateway in t.publishers and not t.service}
        if not inputs:
            print(f"fpga target {target}: no topic from software into its hardware nodes: no chain to time\n")
            continue
        samples = {name: sample_message(types, typename, (int(width), int(height)), args.size,
                                        channels=channels_of(plan, target, name))
                   for name, typename in inputs.items()}
        kinds = ", ".join(f"{name} {getattr(sample, 'encoding', '') or 'arrays'}" for name, sample in samples.items())
        print(f"fpga target {target}: one message into {', '.join(inputs)} ({args.image} for images, {args.size} "
              f"elements for arrays; {kinds}), co-simulated in Verilator; each output checked against the nodes' "
              "software twins\n")
        print(format_models(target, execution_models(plan, target, types, samples)))
        print(_clock_line(plan, target))
    return 0


def cmd_hw_synth(args: argparse.Namespace) -> int:
    _hardware_tools()
    from ..hw import format_synth, part_of, synth_report

    plan, targets = _fpga_targets(args)
    for target in targets:
        part_name = plan.targets[target].part
        part = part_of(part_name)
        family = part.family if part is not None else "xcup"
        print(f"fpga target {target} ({part_name or 'no part named'}): Yosys estimate (synth_xilinx -family {family} "
              "-flatten) per hardware node and topic network, each on its own; not vendor place and route\n")
        print(format_synth(synth_report(plan, target), part_name))
    return 0


def cmd_ps(args: argparse.Namespace) -> int:
    import json
    from dataclasses import asdict

    from ..launch import format_launches, running

    records = running()
    print(json.dumps([asdict(r) for r in records], indent=1) if args.json else format_launches(records))
    return 0


def _seconds(text: str) -> float:
    """A positive, finite number of seconds (``--start-timeout``)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, not {text!r}")
    return value


def _launch_file_kind(path: Path) -> str | None:
    """``ros2launch`` or ``roslaunch`` for a ROS launch file (what ``ros2 launch``/``roslaunch`` take), else None."""
    name = path.name
    if name.endswith(".py") or name.endswith((".launch.xml", "_launch.xml", ".launch.yaml", "_launch.yaml")):
        return "ros2launch"
    return "roslaunch" if name.endswith(".launch") else None


def _launch_arguments(words: list[str]) -> dict[str, str]:
    found = {}
    for word in words:
        name, sep, value = word.partition(":=")
        if not sep or not name:
            raise ProjectError(f"a launch argument is NAME:=VALUE, not {word!r}")
        found[name] = value
    return found


def cmd_launch(args: argparse.Namespace) -> int:
    from ..launch import launch
    from ..project import import_launch, plan_file
    from ..runtime import NODE_TIMES_VARIABLE

    kind = _launch_file_kind(Path(args.project))
    if args.launch_args and kind is None:
        raise ProjectError(f"NAME:=VALUE arguments are a launch file's; {args.project} is a project file")
    if kind is not None:  # a ROS launch file: imported into a project of the launch's own, then launched
        folder = Path(tempfile.mkdtemp(prefix="hetros-launch-", dir=os.environ.get("XDG_RUNTIME_DIR")))
        atexit.register(shutil.rmtree, folder, True)
        project, notes = import_launch(Path(args.project), kind == "ros2launch",
                                       [Path(p) for p in args.package_path or []], folder,
                                       _launch_arguments(args.launch_args))
        for note in notes:
            print(f"[launch] {note}", file=sys.stderr)
        args.project = str(folder / "project.yaml")
        Path(args.project).write_text(yaml.safe_dump(project, sort_keys=False), encoding="utf-8")
    plan = plan_file(args.project)
    if args.node_times:
        os.environ[NODE_TIMES_VARIABLE] = "1"  # the worker processes inherit it
    if args.hw_stalls:
        from ..hw import STALLS_VARIABLE, stall_setting

        os.environ[STALLS_VARIABLE] = args.hw_stalls  # the workers inherit it
        stall_setting()  # refused here, by name, before anything starts
    if args.trace is not None:
        from ..hw import TRACE_VARIABLE, TraceSetting

        os.environ[TRACE_VARIABLE] = TraceSetting(Path(args.trace).resolve(), args.trace_window,
                                                  args.trace_ports).environment()
    result = launch(plan, duration=args.duration, host=args.as_host,
                    record=Path(args.record) if args.record else None, start_timeout=args.start_timeout)
    if result.exit_code:
        print(f"[launch] graph stopped: {result.reason} (failed: {', '.join(result.failures) or '-'})",
              file=sys.stderr)
    return result.exit_code


def cmd_deploy(args: argparse.Namespace) -> int:
    from ..launch import deploy, deploy_commands
    from ..project import plan_file

    plan = plan_file(args.project)
    if args.print:
        for host, command in deploy_commands(plan, Path(args.project), remote=args.remote,
                                             duration=args.duration).items():
            print(f"{host}: {shlex.join(command)}")
        return 0
    return deploy(plan, Path(args.project), remote=args.remote, duration=args.duration)


def cmd_init(args: argparse.Namespace) -> int:
    from ..project import ros_template, template_from_sources, writes_ros

    files = [Path(f) for f in args.files]
    missing = [str(f) for f in files if not f.exists()]
    if missing:
        print(f"error: no such file or folder: {', '.join(missing)}", file=sys.stderr)
        return EXIT_ERROR
    root = Path(args.root) if args.root else (files[0].parent if files else Path.cwd())
    name = args.name or re.sub(r"[^A-Za-z0-9_-]", "_", root.resolve().name).lstrip("_-0123456789") or "project"
    base = Path(args.output).parent if args.output else Path.cwd()
    if any(f.is_dir() or writes_ros(f) for f in files):
        data, unresolved = ros_template(files, name, base)
    else:
        data, unresolved = template_from_sources(files, root, name, base)
    if not data["nodes"]:
        print("no nodes found: no create_* calls, ROS entry points (setup.py, setup.cfg) or rospy.init_node in "
              "the given files", file=sys.stderr)
        return EXIT_ERROR
    _write_yaml(data, args.output)
    print(f"found {len(data['nodes'])} node(s): {', '.join(data['nodes'])}", file=sys.stderr)
    for note in unresolved:
        print(f"warning: {note}", file=sys.stderr)
    return 0


def cmd_import(args: argparse.Namespace) -> int:
    from ..project import import_launch, import_reconros, import_roslite

    if args.format in ("roslaunch", "ros2launch"):
        given = dict(item.partition("=")[::2] for item in args.arg or [])
        project, notes = import_launch(Path(args.file), args.format == "ros2launch",
                                       [Path(p) for p in args.package_path or []],
                                       Path(args.output).parent if args.output else Path.cwd(), given)
        _write_yaml(project, args.output, notes.file_mode)
        for note in notes:
            print(f"warning: {note}", file=sys.stderr)
        print(f"imported {len(project['nodes'])} node(s): {', '.join(project['nodes'])}", file=sys.stderr)
        return 0
    if args.format == "roslite":
        _write_yaml(import_roslite(Path(args.file), module=args.module), args.output)
        return 0
    project, reconros_notes = import_reconros(Path(args.file), module=args.module)
    _write_yaml(project, args.output)
    for note in reconros_notes:
        print(f"note: {note}", file=sys.stderr)
    return 0


def _load_types(args: argparse.Namespace) -> None:
    for folder in args.messages or []:
        registry().load_folder(Path(folder))


def cmd_msg_show(args: argparse.Namespace) -> int:
    _load_types(args)
    types = registry()
    name = args.type
    for kind, table in (("srv", types.services), ("action", types.actions)):
        try:
            from ..msg import normalize_typename

            full = normalize_typename(name, kind)
        except Error:
            continue
        if full in table:
            parts = ("Request", "Response") if kind == "srv" else ("Goal", "Result", "Feedback")
            print("\n---\n".join(types.definition_text(f"{full}_{p}").rstrip() for p in parts))
            return 0
    print(types.definition_text(name).rstrip())
    return 0


def cmd_msg_list(args: argparse.Namespace) -> int:
    _load_types(args)
    for name in registry().names():
        print(name)
    return 0


def cmd_msg_layout(args: argparse.Namespace) -> int:
    from ..msg import flat_layout

    _load_types(args)
    types = registry()
    print(flat_layout(types, args.type).describe())
    codec = types.codec(args.type)
    if codec.compiled:
        how = "compiled (hetros.msg._ccdr)"
    elif codec.generated:
        why = "HETROS_PURE_PYTHON is set" if not compiled_wanted() else "the C extension is not built"
        how = f"generated Python ({why})"
    else:
        how = "rosbags (a field the generator does not cover)"
    print(f"codec: {how}")
    return 0


def cmd_msg_build(args: argparse.Namespace) -> int:
    from ..msg import build_package_modules

    for path in build_package_modules(Path(args.folder), Path(args.output)):
        print(f"wrote {path}")
    return 0


def cmd_msg_stubs(args: argparse.Namespace) -> int:
    from ..msg import shipped_stubs, user_stubs
    from ..project import load_project

    if args.shipped:
        for path, text in shipped_stubs().items():
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
        print(f"wrote the shipped packages' stubs under {path.parent.parent}")
        return 0
    folders: list[Path] = []
    for given in map(Path, args.sources):
        if given.is_file():  # a project file: its messages: folders
            loaded = load_project(given)
            folders += [loaded.root / folder for folder in loaded.model.messages]
        elif given.is_dir():
            folders.append(given)
        else:
            raise ProjectError(f"{given}: not a project file nor a folder of interface packages")
    written = user_stubs(folders, Path(args.output))
    packages = sorted({path.parent.name for path in written})
    print(f"wrote the stubs of {', '.join(packages) or 'no package'} under {args.output}/hetros/interfaces; "
          f"type-check with MYPYPATH={args.output} mypy ...")
    return 0


def cmd_reference(args: argparse.Namespace) -> int:
    from ..project import reference_markdown

    print(reference_markdown(), end="")
    return 0


def cmd_master(args: argparse.Namespace) -> int:
    import threading

    from .._signals import wait_until_set
    from ..runtime import setup_logging
    from ..transport.tcpros import Master

    setup_logging()
    master = Master(args.host, args.port)
    print(f"ROS master at {master.uri} (ROS_MASTER_URI={master.uri}); Ctrl-C stops it", flush=True)
    try:
        wait_until_set(threading.Event())  # until a stop signal ends the process
    finally:
        master.close()
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    # the benchmarks' roles and peers are a package of their own (benchmarks/hetros_bench), not the library's
    try:
        import hetros_bench  # noqa: F401
    except ImportError as exc:
        print(f"the benchmarks are not installed ({exc}): run `make install-bench` in a hetros checkout "
              "(pip install -e '.[bench]' -e benchmarks)", file=sys.stderr)
        return EXIT_ERROR
    if args.bench == "hw":
        _hardware_tools()
        from hetros_bench.hw import main as hardware

        return hardware((["--quick"] if args.quick else []) + (["--out", args.out] if args.out else []))
    try:
        from hetros_bench.latency import main as latency
        from hetros_bench.ros1 import main as ros1
    except ImportError as exc:
        print(f"the benchmark needs the bench extra: run `make install-bench` ({exc})", file=sys.stderr)
        return EXIT_ERROR
    forwarded = ["--quick"] if args.quick else []
    if args.out:
        forwarded += ["--out", args.out]
    if getattr(args, "sizes", None):  # latency and ros1 take it, dds does not
        forwarded += ["--sizes", args.sizes]
    if args.bench == "ros1":
        rounds = ["--rounds", str(args.rounds)] if args.rounds else []
        return ros1([*forwarded, *rounds, "--gap-ms", str(args.gap_ms), "--settle-us", str(args.settle_us),
                     *(["--steady-malloc"] if args.steady_malloc else [])])
    if args.bench == "dds":
        from hetros_bench.dds import main as dds

        return dds(forwarded)
    if args.systems:
        forwarded += ["--systems", args.systems]
    if args.rounds:
        forwarded += ["--rounds", str(args.rounds)]
    return latency(forwarded)


_SIZES_HELP = "comma-separated subset of the sizes, as the tables label them or in bytes (e.g. 4B,196kB)"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="hetros", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("check", help="validate a project file")
    p.add_argument("project")
    p.add_argument("--resolved", action="store_true", help="also print each node with its namespace, remaps, "
                   "parameters and endpoints, as groups, instances and includes resolve them")
    p.set_defaults(func=cmd_check)
    p = sub.add_parser("graph", help="print the computation and architecture graphs")
    p.add_argument("project", nargs="?", help="the project file (with --live: picks its running launch)")
    p.add_argument("--out", help="write <out>.dot and <out>.svg")
    p.add_argument("--live", action="store_true", help="of a running launch, with each topic's rate on its edges")
    p.add_argument("--session", help="with --live: the launch's session (hetros ps)")
    p.set_defaults(func=cmd_graph)
    p = sub.add_parser("launch", help="run a project, or a ROS launch file (Python, XML, YAML; ROS 1 .launch)")
    p.add_argument("project", help="a project file, or a launch file (imported as `hetros import` does)")
    p.add_argument("launch_args", nargs="*", metavar="NAME:=VALUE", help="a launch file's arguments")
    p.add_argument("--package-path", action="append", metavar="DIR",
                   help="a launch file's packages are found under this folder (repeatable; also $HETROS_PACKAGE_PATH, "
                        "and the folder holding the launch file's own package)")
    p.add_argument("--duration", type=seconds, help="stop after this many seconds")
    p.add_argument("--start-timeout", type=_seconds, default=60.0,
                   help="seconds the targets may take to start, a simulator's announced compilation not counted "
                        "(default 60)")
    p.add_argument("--as", dest="as_host", metavar="HOST",
                   help="with hosts: run this host's targets (default: the host whose address is this machine's)")
    p.add_argument("--record", metavar="RUN.MCAP", help="record every topic into this MCAP file while it runs")
    p.add_argument("--node-times", action="store_true",
                   help="at the end, log each node's time per message on each subscription and service")
    p.add_argument("--hw-stalls", metavar="SEED[:PERCENT]",
                   help="co-simulated fpga targets: every gateway port stalls on PERCENT %% of cycles (default 25), "
                        "drawn from SEED, and the AXI4-Stream checker on each port stops the launch on a violation")
    p.add_argument("--trace", metavar="FOLDER",
                   help="co-simulated fpga targets: write each target's waveform to FOLDER/<target>.vcd (GTKWave, "
                        "Surfer), the last --trace-window cycles before the end or the error that stopped it")
    p.add_argument("--trace-window", metavar="CYCLES", type=positive_count, default=TRACE_WINDOW,
                   help="--trace keeps at least this many of the last cycles, at most twice as many "
                        "(default %(default)s)")
    p.add_argument("--trace-ports", action="store_true",
                   help="--trace only the top module's ports (the gateway's streams), not every signal inside")
    p.set_defaults(func=cmd_launch)
    from ._advise import add_parser as add_advise

    add_advise(sub)
    p = sub.add_parser("deploy", help="start every host of a project (this one directly, the others over ssh)")
    p.add_argument("project")
    p.add_argument("--duration", type=seconds, help="stop after this many seconds")
    p.add_argument("--remote", default="python3 -m hetros",
                   help="how a remote host runs hetros in the project's folder (default: %(default)s)")
    p.add_argument("--print", action="store_true", help="print each host's command instead of running it")
    p.set_defaults(func=cmd_deploy)
    p = sub.add_parser("init", help="write a project from node sources: hetros nodes, or rclpy and rospy "
                                     "packages (their entry points) and files")
    p.add_argument("files", nargs="+", help="Python files, or ROS package folders (setup.py/setup.cfg entry points, "
                   "rospy scripts)")
    p.add_argument("-o", "--output")
    p.add_argument("--name")
    p.add_argument("--root", help="folder the modules are relative to (default: the first file's)")
    p.set_defaults(func=cmd_init)
    p = sub.add_parser("import", help="a project from a ROS 1 launch file, a ROS 2 launch file (XML, YAML), a "
                                       "ROS-lite .map or a ReconROS build.cfg")
    p.add_argument("format", choices=["roslaunch", "ros2launch", "roslite", "reconros"])
    p.add_argument("file")
    p.add_argument("-o", "--output")
    p.add_argument("--module", default="nodes", help="module holding the node functions (roslite, reconros)")
    p.add_argument("--package-path", action="append", metavar="DIR",
                   help="a folder the launch file's packages are found under (repeatable; the launch file's own "
                        "folder is searched too)")
    p.add_argument("--arg", action="append", metavar="NAME=VALUE", help="a launch argument (repeatable)")
    p.set_defaults(func=cmd_import)
    p = sub.add_parser("reference", help="print the project file's reference (every key, kind and default)")
    p.set_defaults(func=cmd_reference)
    p = sub.add_parser("master", help="run a ROS 1 master (master API + parameter server) for rospy/roscpp nodes")
    p.add_argument("--port", type=port, default=11311)
    p.add_argument("--host", default="127.0.0.1", help="interface to listen on (default 127.0.0.1 only)")
    p.set_defaults(func=cmd_master)
    bench = sub.add_parser("bench", help="benchmarks against the peers").add_subparsers(dest="bench", required=True)
    p = bench.add_parser("latency", help="latency, throughput and idle CPU against CycloneDDS, iceoryx2, ...")
    p.add_argument("--quick", action="store_true",
                        help="fewer sizes and repetitions (about a minute on 2 cores)")
    p.add_argument("--out", help="output folder (default out/bench)")
    p.add_argument("--systems", help="comma-separated subset")
    p.add_argument("--rounds", type=positive_count, help="interleaved rounds whose samples are pooled (default 1)")
    p.add_argument("--sizes", help=_SIZES_HELP)
    p.set_defaults(func=cmd_bench)
    p = bench.add_parser("hw", help="hardware topics: simulated transfer times and Yosys resources vs fpgaDDS")
    p.add_argument("--quick", action="store_true", help="sizes up to 196 kB, two networks")
    p.add_argument("--out", help="output folder (default out/bench)")
    p.set_defaults(func=cmd_bench)
    p = bench.add_parser("dds", help="hetros's DDS transport against the raw cyclonedds binding and ddsperf")
    p.add_argument("--quick", action="store_true")
    p.add_argument("--out", help="output folder (default out/bench)")
    p.set_defaults(func=cmd_bench)
    p = bench.add_parser("ros1", help="one-way latency over TCPROS: rospy and hetros nodes, both ways")
    p.add_argument("--quick", action="store_true", help="fewer repetitions")
    p.add_argument("--settle-us", type=microseconds, default=50.0,
                   help="sender's wait, awake, after each reply (default 50; 0: back-to-back exchanges)")
    p.add_argument("--gap-ms", type=milliseconds, default=0.0,
                   help="sender's pause after each reply (isolated messages)")
    p.add_argument("--rounds", type=positive_count,
                   help="interleaved rounds over every pair and size, pooled (default 3)")
    p.add_argument("--steady-malloc", action="store_true",
                   help="every process keeps large buffers mapped (GLIBC_TUNABLES; see benchmarks/ros1.py)")
    p.add_argument("--sizes", help=_SIZES_HELP)
    p.add_argument("--out", help="output folder (default out/bench)")
    p.set_defaults(func=cmd_bench)
    p = sub.add_parser("ps", help="the launches running on this machine as you: session, pid, project, hosts, start")
    p.add_argument("--json", action="store_true", help="as JSON, for machines")
    p.set_defaults(func=cmd_ps)
    from ._inspect import add_commands

    add_commands(sub)
    hw = sub.add_parser("hw", help="fpga targets: topic networks as RTL").add_subparsers(dest="hw", required=True)

    def written(name: str, what: str, output: str, func: Callable[[argparse.Namespace], int]) -> Any:
        """A command writing files for a project's fpga targets: project, -o, --target."""
        made = hw.add_parser(name, help=what)
        made.add_argument("project")
        made.add_argument("-o", "--output", required=True, help=output)
        made.add_argument("--target", help="the fpga target (default: every one)")
        made.set_defaults(func=func)
        return made

    written("build", "write an fpga target's topic network as Verilog, with a JSON manifest",
            "folder for <top>.v and <top>.json", cmd_hw_build)
    p = written("export", "an fpga target as a Vivado project for a board: Verilog, AXI wrapper, block-design Tcl, "
                "manifest", "the folder (one per target when there are several)", cmd_hw_export)
    p.add_argument("--board", choices=["zcu104", "pynq-z2", "ultra96"], help="default: the target's board:")
    p = written("bitstream", "a real bitstream on the open flow (YoWASP Yosys + nextpnr, Lattice ECP5) and the Fmax "
                "place and route achieved", "the folder (a subfolder per target and design)", cmd_hw_bitstream)
    p.add_argument("--parts", choices=["all", "target", "parts"], default="all",
                   help="target: the whole target; parts: each hardware node and topic network alone")
    p = hw.add_parser("report", help="simulated transfer time per message size (fpgaDDS Table I sizes)")
    p.add_argument("project")
    p.add_argument("--target", help="the fpga target (default: every one)")
    p.add_argument("--simulator", choices=["auto", "icarus", "amaranth"], default="auto",
                   help="auto: Icarus Verilog when installed (fast), else Amaranth's simulator")
    p.add_argument("--models", action="store_true",
                   help="instead: the target's hardware nodes as a dataflow chain (hardware topics between them) "
                        "and as a sequential one (each behind its own gateway): latency and CPU copies per message")
    p.add_argument("--image", default="640x480", help="--models: the size of an image message (WIDTHxHEIGHT)")
    p.add_argument("--size", type=positive_count, default=2048, help="--models: elements of an array message")
    p.set_defaults(func=cmd_hw_report)
    p = hw.add_parser("synth", help="Yosys resource estimate (LUT/FF/BRAM/DSP) per hardware node and topic network, "
                                       "totals against the part")
    p.add_argument("project")
    p.add_argument("--target", help="the fpga target (default: every one)")
    p.set_defaults(func=cmd_hw_synth)
    msg = sub.add_parser("msg", help="message types").add_subparsers(dest="msg_command", required=True)
    p = msg.add_parser("show", help="print a type's full definition")
    p.add_argument("type")
    p.add_argument("--messages", action="append", help="extra package folder(s)")
    p.set_defaults(func=cmd_msg_show)
    p = msg.add_parser("list", help="list known message types")
    p.add_argument("--messages", action="append")
    p.set_defaults(func=cmd_msg_list)
    p = msg.add_parser("layout", help="print the flattened primitive layout (offsets, sizes)")
    p.add_argument("type")
    p.add_argument("--messages", action="append")
    p.set_defaults(func=cmd_msg_layout)
    p = msg.add_parser("build", help="write importable, typed modules for a package")
    p.add_argument("folder")
    p.add_argument("-o", "--output", required=True)
    p.set_defaults(func=cmd_msg_build)
    p = msg.add_parser("stubs", help="write typed stubs of a project's interface packages, for mypy and IDEs")
    p.add_argument("sources", nargs="*", metavar="PROJECT_OR_FOLDER",
                   help="project files (their messages: folders) or folders of interface packages")
    p.add_argument("-o", "--output", default="typings", help="the folder to put on MYPYPATH (default typings)")
    p.add_argument("--shipped", action="store_true",
                   help="regenerate the stubs of the packages hetros ships (a development task)")
    p.set_defaults(func=cmd_msg_stubs)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    with contextlib.suppress(OSError, ValueError):  # stderr that is no file (a caller's buffer) has no crash log
        faulthandler.enable()  # a crash in native code names itself (and where) instead of a bare exit status
    args = build_parser().parse_args(argv)
    if args.func is not cmd_launch:  # the launcher installs its own handlers (see hetros._signals)
        interruptible()
    try:
        code: int = args.func(args)
        return code
    except Error as exc:
        print(f"error: {printable(str(exc))}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our output left (`hetros msg list | head`): nothing is wrong, stop quietly
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except (Exception, RecursionError) as exc:  # a defect of hetros: one line here, the traceback in a file
        where = _write_crash_report(exc)
        print(f"error: hetros failed unexpectedly ({type(exc).__name__}: {printable(str(exc))[:300]}); this is a "
              f"bug in hetros, not in your input: the full traceback is in {where}; please report it",
              file=sys.stderr)
        return EXIT_BUG


def _write_crash_report(exc: BaseException) -> str:
    """The traceback of ``exc`` in a file of this user's private folder (its path), else on stderr."""
    import traceback

    text = "".join(traceback.format_exception(exc))
    try:
        from .._paths import user_subfolder

        given = os.environ.get(CRASH_DIR_VARIABLE)
        if given:
            os.makedirs(given, mode=0o700, exist_ok=True)
        folder = Path(given) if given else user_subfolder("crashes")
        path = folder / f"hetros-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.txt"
        descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(descriptor, "w", encoding="utf-8") as out:
            out.write(f"hetros {' '.join(sys.argv[1:])}\n\n{text}")
        return str(path)
    except (OSError, Error):
        sys.stderr.write(text)
        return "the lines above"
