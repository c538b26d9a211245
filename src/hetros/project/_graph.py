"""``hetros graph``: the computation graph and the architecture graph of a plan."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from .._errors import Error
from ..plan import ACTION_PREFIX, ROS2_BRIDGE, Plan


def _rate(rates: dict[str, float] | None, topic: str) -> str:
    return "" if rates is None else f" {rates.get(topic, 0.0):.1f} Hz"


def describe(plan: Plan, rates: dict[str, float] | None = None) -> str:
    """The graphs as text; with ``rates`` (a running launch's, topic -> Hz), each topic's rate."""
    lines = [f"project {plan.name}", "", "computation graph (nodes and topics):"]
    for name, node in plan.nodes.items():
        for action, typename in node.actions.items():
            callers = [n for n, other in plan.nodes.items() if action in other.action_clients]
            lines.append(f"  action {action} [{typename}]  {', '.join(callers) or '(no client)'} -> {name}  "
                         f"(up to {node.max_goals.get(action, 1)} goals at once; its services and topics "
                         f"under {action.rstrip('/')}{ACTION_PREFIX})")
    for channel in plan.channels.values():
        if ACTION_PREFIX in channel.name:
            continue
        if channel.kind == "topic":
            lines.append(f"  {channel.name} [{channel.type}]  {', '.join(channel.publishers)} -> "
                         f"{', '.join(channel.subscribers) or '(no subscriber)'}"
                         + (f"  ({_rate(rates, channel.name).strip()})" if rates is not None else ""))
        elif channel.kind == "request":
            lines.append(f"  service {channel.service} [{channel.type.removesuffix('_Request')}]  "
                         f"{', '.join(channel.publishers) or '(no client)'} -> {', '.join(channel.subscribers)}")
    lines += ["", "architecture graph (targets and transports):"]
    for target in plan.targets.values():
        members = [n for n, spec in plan.nodes.items() if spec.target == target.name]
        if not members:
            continue
        where = "threads of the launcher" if target.kind == "thread" else (
            f"own process, cpus {list(target.cpus)}" if target.cpus else "own process")
        if target.kind == "fpga":
            where = (f"{target.part or 'any part'}, topic network at {target.clock_mhz:g} MHz, "
                     f"{target.data_width}-bit AXI-Stream")
        if plan.hosts:
            host = plan.hosts[target.host]
            where += f", on host {host.name} ({host.address})"
        lines.append(f"  target {target.name} ({target.kind}: {where}): {', '.join(members)}")
    for edge in plan.edges:
        q = plan.channels[edge.channel].qos
        how = (f"FIFO of {q.hw_fifo} beats" if q.hw_fifo else "no FIFO") if edge.transport == "hw" else \
            f"{q.reliability}, {q.history}, depth {q.depth}"
        lines.append(f"  {edge.publisher} -> {edge.subscriber}  {edge.channel}  via {edge.transport}  ({how})")
    for name, node in plan.nodes.items():
        if not plan.speaks_ros1(name):
            continue
        for what, table in (("publishes", node.publish), ("subscribes", node.subscribe),
                            ("serves", node.services), ("calls", node.clients)):
            for endpoint, typename in table.items():
                lines.append(f"  {name} {what} {endpoint} [{typename}]  via tcpros (ROS 1 master {plan.ros1_master})")
    lines += _ros2_lines(plan)
    return "\n".join(lines)


def _ros2_lines(plan: Plan) -> list[str]:
    """What crosses to ROS 2, under the DDS names a ROS 2 peer sees."""
    from ..transport.dds import reply_topic, request_topic, topic_name

    bridge = plan.nodes.get(ROS2_BRIDGE)
    if bridge is None:
        return []
    p = bridge.parameters
    domain = p["domain"] if p["domain"] is not None else "$ROS_DOMAIN_ID or 0"
    where = f"ROS 2 domain {domain}, peers {', '.join(p['peers'])}"
    lines = []
    for section, verb in (("export", "exported to"), ("import", "imported from")):
        for topic, typename in p[section].items():
            lines.append(f"  {topic} [{typename}] {verb} ROS 2 as {topic_name(topic)}  via dds ({where})")
    for section, verb in (("export_services", "served to"), ("import_services", "called from")):
        for service, typename in p[section].items():
            lines.append(f"  {service} [{typename}] {verb} ROS 2 as {request_topic(service)} / "
                         f"{reply_topic(service)}  via dds ({where})")
    return lines


def to_dot(plan: Plan, rates: dict[str, float] | None = None) -> str:
    out = ["digraph hetros {", "  rankdir=LR;", '  node [fontname="Helvetica"];']
    for target in plan.targets.values():
        members = [n for n, spec in plan.nodes.items() if spec.target == target.name]
        if not members:
            continue
        out.append(f'  subgraph "cluster_{target.name}" {{')
        out.append(f'    label="{target.name} ({target.kind})"; style=rounded;')
        for node in members:
            out.append(f'    "{node}" [shape=box];')
        out.append("  }")
    for channel in plan.channels.values():
        if channel.kind == "topic":
            out.append(f'  "{channel.name}" [shape=ellipse, label="{channel.name}\\n{channel.type}"];')
    for edge in plan.edges:
        channel = plan.channels[edge.channel]
        style = "solid" if edge.transport == "inproc" else "bold"
        if channel.kind == "topic":
            label = f"{edge.transport}{_rate(rates, channel.name)}"
            out.append(f'  "{edge.publisher}" -> "{channel.name}" [label="{label}", style={style}];')
            out.append(f'  "{channel.name}" -> "{edge.subscriber}" [label="{label}", style={style}];')
        elif channel.kind == "request":
            out.append(f'  "{edge.publisher}" -> "{edge.subscriber}" [label="{channel.service} '
                       f'({edge.transport})", style=dashed];')
    out.append("}")
    unique: list[str] = []
    for line in out:
        if "->" not in line or line not in unique:
            unique.append(line)
    return "\n".join(unique) + "\n"


def write_graph(plan: Plan, out: Path, rates: dict[str, float] | None = None) -> list[Path]:
    """Write ``<out>.dot`` and render ``<out>.svg`` with Graphviz."""
    return render_svg(to_dot(plan, rates), out)


def render_svg(dot: str, out: Path) -> list[Path]:
    """Write the Graphviz source ``dot`` to ``<out>.dot`` and render ``<out>.svg``: Graphviz's ``dot`` where
    installed, else graphviz-pure (a dependency of hetros)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    dot_path = out.with_suffix(".dot")
    dot_path.write_text(dot, encoding="utf-8")
    svg_path = out.with_suffix(".svg")
    beside = Path(sys.executable).parent / "graphviz-pure"
    renderer = shutil.which("dot") or shutil.which("graphviz-pure") or (str(beside) if beside.exists() else None)
    if renderer is None:
        raise Error(f"wrote {dot_path}, but found no Graphviz 'dot' to render SVG: "
                    "install graphviz (apt) or graphviz-pure (pip)")
    result = subprocess.run([renderer, "-Tsvg", str(dot_path), "-o", str(svg_path)],
                            capture_output=True, text=True, check=False)
    if result.returncode != 0:
        raise Error(f"Graphviz failed to render {dot_path}: {result.stderr.strip()}")
    return [dot_path, svg_path]
