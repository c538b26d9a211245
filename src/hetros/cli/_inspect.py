"""``hetros topic|node|service|param|top``: ROS 2's command line, pointed at a running launch.

Names, options and output follow ``ros2 topic``, ``ros2 node``, ``ros2 service`` and
``ros2 param`` so that a ROS user's hands already know them; ``--session`` or ``--project``
picks the launch when more than one runs (``hetros ps`` lists them).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import deque
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, cast

import yaml

from .._errors import Error, InspectError
from .._files import load_yaml
from ..launch import LaunchLogs, RunningLaunch, TapEvent
from ..msg import DEFAULT_TRUNCATE_LENGTH, Message, from_plain, normalize_typename, to_plain
from ..plan import ACTION_PREFIX, PARAMETER_SERVICES, Plan, join_namespace
from . import _args as numbers

# ros2 topic hz's default window (messages)
HZ_WINDOW = 10000
# ros2 topic bw's default window (messages)
BW_WINDOW = 100


def _launch(args: argparse.Namespace) -> RunningLaunch:
    return RunningLaunch.find(args.session, args.project)


def _hidden(name: str) -> bool:
    return ACTION_PREFIX in name


def _dump(data: Any, flow: bool = False) -> str:
    return str(yaml.safe_dump(data, allow_unicode=True, width=sys.maxsize, default_flow_style=flow,
                              sort_keys=False))


def _values(text: str, where: str) -> Any:
    try:
        return yaml.safe_load(text) if text.strip() else {}
    except yaml.YAMLError as exc:
        raise InspectError(f"{where}: {text!r} is not YAML ({exc}); write values as \"{{data: hello}}\"") from None


# -- topic --------------------------------------------------------------------------------------


def cmd_topic_list(args: argparse.Namespace) -> int:
    launch = _launch(args)
    for name, channel in sorted(launch.plan.channels.items()):
        if channel.kind == "topic" and (args.include_hidden_topics or not _hidden(name)):
            print(f"{name} [{channel.type}]" if args.show_types else name)
    return 0


def cmd_topic_info(args: argparse.Namespace) -> int:
    launch = _launch(args)
    typename = launch.topic(args.topic)
    channel = launch.plan.channels[args.topic]
    print(f"Type: {typename}" + ("\n" if args.verbose else ""))
    for role, nodes in (("Publisher", channel.publishers), ("Subscription", channel.subscribers)):
        print(f"{role} count: {len(nodes)}" + ("\n" if args.verbose else ""))
        if not args.verbose:
            continue
        for node in nodes:
            spec = launch.plan.nodes[node]
            edges = launch.plan.edges_of(args.topic, node, "publish" if role == "Publisher" else "subscribe")
            transports = ", ".join(sorted({e.transport for e in edges})) or "-"
            where = "hardware" if launch.plan.in_hardware(node) else launch.plan.process_of(node)
            qos = channel.qos
            namespace = join_namespace("", spec.namespace) or "/"
            print(f"Node name: {node}\nNode namespace: {namespace}\nTopic type: {typename}\n"
                  f"Endpoint type: {role.upper()}\nTarget: {spec.target} ({where})\nTransports: {transports}\n"
                  f"QoS profile:\n  Reliability: {qos.reliability.upper()}\n  History (Depth): "
                  f"{qos.history.upper()} ({qos.depth})\n  Durability: {qos.durability.upper()}\n")
    return 0


def cmd_topic_type(args: argparse.Namespace) -> int:
    print(_launch(args).topic(args.topic))
    return 0


def cmd_topic_find(args: argparse.Namespace) -> int:
    launch = _launch(args)
    wanted = normalize_typename(args.type, "msg")
    for name, channel in sorted(launch.plan.channels.items()):
        if channel.kind == "topic" and channel.type == wanted and (args.include_hidden_topics or not _hidden(name)):
            print(name)
    return 0


def _field(message: Message, path: str) -> Any:
    value: Any = message
    for part in filter(None, path.split(".")):
        if not hasattr(value, part):
            raise InspectError(f"--field {path}: {type(value).__name__} has no field {part!r}")
        value = getattr(value, part)
    return value


def cmd_topic_echo(args: argparse.Namespace) -> int:
    launch = _launch(args)
    typename = launch.topic(args.topic)
    truncate = None if args.full_length else args.truncate_length

    def render(event: TapEvent) -> str:
        assert event.data is not None
        message = launch.decode(typename, event.data)
        value = _field(message, args.field) if args.field else message
        if isinstance(value, Message):
            plain: Any = to_plain(launch.types, value, truncate_length=truncate, no_arr=args.no_arr,
                                  no_str=args.no_str)
            text = _dump(plain, args.flow_style)
        else:
            text = _dump(value.tolist() if hasattr(value, "tolist") else value, args.flow_style)
            text = text[:-len("...\n")] if text.endswith("...\n") else text
        if args.lost_messages and event.dropped:
            text = (f"A message was lost!!!\n\ttotal count change:{event.dropped}\n\ttotal count: "
                    f"{event.dropped}\n") + text
        return text
    return _echo(launch.tap(args.topic, data=True), render, args)


def _echo(events: Iterable[TapEvent | None], render: Callable[[TapEvent], str], args: argparse.Namespace) -> int:
    """What ``topic echo`` and ``service echo`` share: each event with data as ``render`` gives it, then
    ``---``, until ``--once``, ``-n`` or ``--duration`` says to stop."""
    wanted = 1 if args.once else args.times
    shown = 0
    deadline = None if args.duration is None else time.monotonic() + args.duration
    for event in events:
        if deadline is not None and time.monotonic() > deadline:
            break
        if event is None or event.data is None:
            continue
        sys.stdout.write(render(event) + "---\n")
        sys.stdout.flush()
        shown += 1
        if wanted and shown >= wanted:
            break
    return 0


def _every_second(launch: RunningLaunch, topic: str, duration: float | None, data: bool,
                  seen: Callable[[TapEvent], None], report: Callable[[], None]) -> int:
    """Feed ``seen`` each message of ``topic`` and call ``report`` once a second, as ros2 topic hz does."""
    launch.topic(topic)
    start = time.monotonic()
    next_report = start + 1.0
    for event in launch.tap(topic, data=data):
        now = time.monotonic()
        if event is not None:
            seen(event)
        if now >= next_report:
            report()
            next_report = now + 1.0
        if duration is not None and now - start >= duration:
            break
    return 0


def _spread(values: Iterable[float]) -> tuple[float, float, float, float]:
    """(mean, min, max, population std dev)."""
    items = list(values)
    mean = sum(items) / len(items)
    return mean, min(items), max(items), math.sqrt(sum((v - mean) ** 2 for v in items) / len(items))


def cmd_topic_hz(args: argparse.Namespace) -> int:
    launch = _launch(args)
    times: deque[int] = deque(maxlen=args.window + 1)

    def report() -> None:
        if len(times) < 2:
            print("no new messages")
            return
        deltas = [(b - a) / 1e9 for a, b in zip(list(times)[:-1], list(times)[1:], strict=True)]
        mean, low, high, std = _spread(deltas)
        print(f"average rate: {1.0 / mean if mean > 0 else 0.0:.3f}\n\tmin: {low:.3f}s max: {high:.3f}s "
              f"std dev: {std:.5f}s window: {len(deltas)}", flush=True)

    return _every_second(launch, args.topic, args.duration, False, lambda e: times.append(e.time_ns), report)


def _bytes(value: float) -> str:
    if value < 1000:
        return f"{value:.0f} B"
    if value < 1000 * 1000:
        return f"{value / 1000:.2f} KB"
    return f"{value / 1e6:.2f} MB"


def cmd_topic_bw(args: argparse.Namespace) -> int:
    launch = _launch(args)
    seen: deque[tuple[int, int]] = deque(maxlen=args.window)
    print(f"Subscribed to [{args.topic}]", flush=True)

    def report() -> None:
        if len(seen) < 2:
            return
        span = (time.time_ns() - seen[0][0]) / 1e9
        sizes = [size for _, size in seen]
        mean, low, high, _ = _spread(sizes)
        rate = sum(sizes) / span if span > 0 else 0.0
        print(f"{_bytes(rate)}/s from {len(sizes)} messages\n\tMessage size mean: {_bytes(mean)} "
              f"min: {_bytes(low)} max: {_bytes(high)}", flush=True)

    return _every_second(launch, args.topic, args.duration, False, lambda e: seen.append((e.time_ns, e.size)),
                         report)


def cmd_topic_delay(args: argparse.Namespace) -> int:
    launch = _launch(args)
    delays: deque[float] = deque(maxlen=args.window)
    stamped = [True]

    def seen(event: TapEvent) -> None:
        if event.stamp is None:
            stamped[0] = False
            return
        delays.append((event.time_ns - event.stamp) / 1e9)

    def report() -> None:
        if not stamped[0]:
            raise InspectError(f"{args.topic}'s messages have no header stamp: delay needs std_msgs/Header")
        if not delays:
            print("no new messages")
            return
        mean, low, high, std = _spread(delays)
        print(f"average delay: {mean:.3f}\n\tmin: {low:.3f}s max: {high:.3f}s std dev: {std:.5f}s "
              f"window: {len(delays)}", flush=True)

    return _every_second(launch, args.topic, args.duration, False, seen, report)


def _python_repr(typename: str, message: Message) -> str:
    """A message as rclpy's repr shows it: ``std_msgs.msg.String(data='hi')``."""
    return f"{typename.rsplit('/', 1)[0].replace('/', '.')}.{message!r}"


def cmd_topic_pub(args: argparse.Namespace) -> int:
    launch = _launch(args)
    typename = launch.topic(args.topic)
    given = normalize_typename(args.type, "msg")
    if given != typename:
        raise InspectError(f"{args.topic} carries {typename}, not {given}")
    message = from_plain(launch.types, typename, _values(args.values, "values"))
    times = 1 if args.once else args.times
    sent = 0
    print("publisher: beginning loop\n", flush=True)
    while True:
        reached = launch.publish(args.topic, message)
        sent += 1
        print(f"publishing #{sent}: {_python_repr(typename, message)}\n", flush=True)
        if not reached:
            print(f"warning: no subscription of {args.topic} is running yet", file=sys.stderr)
        if times and sent >= times:
            return 0
        time.sleep(1.0 / args.rate)


# -- node, service, param -----------------------------------------------------------------------


def ros_name(plan: Plan, node: str) -> str:
    """A node's full ROS name, namespace and name (``/r2/talker``, the project's ``name:`` where it gives
    one): what the CLI shows and accepts."""
    return node if node not in plan.nodes and node.startswith("/") else plan.full_name(node)


def node_key(launch: RunningLaunch, given: str) -> str:
    """The plan's node for a name given on the command line: its full ROS name (``/r2/talker``), or the
    project's key for it (``talker``, relative: no leading /)."""
    plan = launch.plan
    by_ros_name = {ros_name(plan, node): node for node in plan.nodes}
    found = by_ros_name.get(given)
    if found is None and not given.startswith("/"):
        found = given if given in plan.nodes else by_ros_name.get(f"/{given}")
    if found is None:  # a node the code made beside the plan's (rclpy's Node('other') in the same main)
        live = launch.live_nodes()
        found = next((name for name in (given, f"/{given}") if name in live), None)
        if found is None:
            raise InspectError(f"launch {launch.record.session} has no node {given} (its nodes: "
                               f"{', '.join(sorted(set(by_ros_name) | set(live)))})")
    return found


def cmd_node_list(args: argparse.Namespace) -> int:
    launch = _launch(args)
    planned = {ros_name(launch.plan, node) for node in launch.plan.nodes}
    for name in sorted(planned | set(launch.live_nodes())):
        print(name)
    return 0


def cmd_node_info(args: argparse.Namespace) -> int:
    launch = _launch(args)
    name = node_key(launch, args.node)
    spec = launch.plan.nodes.get(name)

    def section(title: str, entries: dict[str, str]) -> None:
        print(f"  {title}:")
        for entry, typename in sorted(entries.items()):
            if args.include_hidden or not _hidden(entry):
                print(f"    {entry}: {typename}")

    print(ros_name(launch.plan, name))
    if spec is None:  # a node the code made beside the plan's: its endpoints are counted as the plan node's
        section("Subscribers", {})
        section("Publishers", {})
        section("Service Servers", {f"{name}/{service}": typename for service, typename in PARAMETER_SERVICES.items()})
        for title in ("Service Clients", "Action Servers", "Action Clients"):
            section(title, {})
        return 0
    section("Subscribers", spec.subscribe)
    section("Publishers", spec.publish)
    builtin = {service: typename for service, (node, typename) in launch.plan.parameter_servers().items()
               if node == name}  # its parameter services (a managed node's lifecycle ones too), as ROS 2 lists
    section("Service Servers", {**spec.services, **builtin})
    section("Service Clients", spec.clients)
    section("Action Servers", spec.actions)
    section("Action Clients", spec.action_clients)
    return 0


def cmd_service_list(args: argparse.Namespace) -> int:
    launch = _launch(args)
    for name in launch.services():
        print(f"{name} [{launch.server_of(name)[1]}]" if args.show_types else name)
    return 0


def cmd_service_type(args: argparse.Namespace) -> int:
    print(_launch(args).server_of(args.service)[1])
    return 0


def cmd_service_find(args: argparse.Namespace) -> int:
    """ros2 service find: the services of one type (``pkg/srv/Type``, or ``pkg/Type``)."""
    launch = _launch(args)
    wanted = normalize_typename(args.type, "srv")
    for name in launch.services():
        if launch.server_of(name)[1] == wanted:
            print(name)
    return 0


def cmd_service_echo(args: argparse.Namespace) -> int:
    """ros2 service echo: each call of a service as its four events (client sent, server received,
    server sent, client received), ``info.event_type`` by name."""
    launch = _launch(args)
    _node, typename = launch.server_of(args.service)
    if args.service_type is not None and normalize_typename(args.service_type, "srv") != typename:
        raise InspectError(f"{args.service} is a {typename}, not a {args.service_type}")
    event_type = f"{typename}_Event"
    launch.types.service_event(typename)
    info_type = launch.types.get("service_msgs/msg/ServiceEventInfo")
    names = {getattr(info_type, name): name for name in ("REQUEST_SENT", "REQUEST_RECEIVED", "RESPONSE_SENT",
                                                          "RESPONSE_RECEIVED")}
    truncate = None if args.full_length else args.truncate_length

    def render(event: TapEvent) -> str:
        assert event.data is not None
        plain: Any = to_plain(launch.types, launch.decode(event_type, event.data), truncate_length=truncate,
                              no_arr=args.no_arr, no_str=args.no_str)
        info = plain.get("info")
        if isinstance(info, dict) and "event_type" in info:
            info["event_type"] = names.get(info["event_type"], info["event_type"])
        return _dump(plain, args.flow_style)
    return _echo(launch.tap_service(args.service), render, args)


def cmd_service_call(args: argparse.Namespace) -> int:
    launch = _launch(args)
    _node, typename = launch.server_of(args.service)
    given = normalize_typename(args.type, "srv")
    if given != typename:
        raise InspectError(f"{args.service} is a {typename}, not a {given}")
    request = from_plain(launch.types, f"{typename}_Request", _values(args.values, "values"))
    print(f"requester: making request: {_python_repr(typename, request)}\n")
    response = launch.call(args.service, request)
    print(f"response:\n{_python_repr(typename, response)}\n")
    return 0


# -- lifecycle (ros2 lifecycle) -------------------------------------------------------------------


def _managed(launch: RunningLaunch, given: str | None) -> list[str]:
    """The managed nodes (``lifecycle:``) asked for: one by name, else all; by full ROS name."""
    managed = sorted(ros_name(launch.plan, n) for n, spec in launch.plan.nodes.items() if spec.lifecycle)
    if given is None:
        return managed
    full = ros_name(launch.plan, node_key(launch, given))
    if full not in managed:
        raise InspectError(f"node {full} is not a managed node (give it lifecycle: in the project file); managed "
                           f"nodes: {', '.join(managed) or 'none'}")
    return [full]


def _transitions(launch: RunningLaunch, node: str, graph: bool = False) -> list[Any]:
    service = f"{node}/get_transition_graph" if graph else f"{node}/get_available_transitions"
    typename = "lifecycle_msgs/srv/GetAvailableTransitions"
    answer: Any = launch.call(service, launch.types.get(f"{typename}_Request")())
    return list(answer.available_transitions)


def _print_transitions(transitions: list[Any]) -> None:
    for item in transitions:
        print(f"- {item.transition.label} [{item.transition.id}]\n\tStart: {item.start_state.label}\n\t"
              f"Goal: {item.goal_state.label}")


def cmd_lifecycle_nodes(args: argparse.Namespace) -> int:
    for node in _managed(_launch(args), None):
        print(node)
    return 0


def cmd_lifecycle_get(args: argparse.Namespace) -> int:
    launch = _launch(args)
    request = launch.types.get("lifecycle_msgs/srv/GetState_Request")()
    nodes = _managed(launch, args.node)
    for node in nodes:
        state = cast(Any, launch.call(f"{node}/get_state", request)).current_state
        print(f"{node}: {state.label} [{state.id}]" if args.node is None else f"{state.label} [{state.id}]")
    return 0


def cmd_lifecycle_list(args: argparse.Namespace) -> int:
    launch = _launch(args)
    _print_transitions(_transitions(launch, _managed(launch, args.node)[0], graph=args.all))
    return 0


def cmd_lifecycle_set(args: argparse.Namespace) -> int:
    """ros2 lifecycle set: a transition by label or id, among those available from the node's state."""
    launch = _launch(args)
    node = _managed(launch, args.node)[0]
    available = _transitions(launch, node)
    chosen = next((t.transition for t in available if args.transition in (t.transition.label,
                                                                          str(t.transition.id))), None)
    if chosen is None:
        print("Unknown transition requested, available ones are:", file=sys.stderr)
        for item in available:
            print(f"- {item.transition.label} [{item.transition.id}]", file=sys.stderr)
        return 1
    typename = "lifecycle_msgs/srv/ChangeState"
    request = launch.types.get(f"{typename}_Request")(transition=chosen)
    if cast(Any, launch.call(f"{node}/change_state", request)).success:
        print("Transitioning successful")
        return 0
    print("Transitioning failed")
    return 1


def cmd_action_list(args: argparse.Namespace) -> int:
    launch = _launch(args)
    for name, typename in sorted(launch.actions().items()):
        print(f"{name} [{typename}]" if args.show_types else name)
    return 0


def cmd_action_info(args: argparse.Namespace) -> int:
    """ros2 action info: the action's clients and servers, by full ROS name (``-t``: with the type)."""
    launch = _launch(args)
    plan = launch.plan
    typename = launch.actions().get(args.action)
    clients = sorted(n for n, spec in plan.nodes.items() if args.action in spec.action_clients)
    if typename is None and not clients:
        raise InspectError(f"launch {launch.record.session} has no action {args.action} (its actions: "
                           f"{', '.join(sorted(launch.actions())) or 'none'})")
    typename = typename or next(plan.nodes[n].action_clients[args.action] for n in clients)
    servers = sorted(n for n, spec in plan.nodes.items() if args.action in spec.actions)
    suffix = f" [{typename}]" if args.show_types else ""
    print(f"Action: {args.action}")
    for role, nodes in (("Action clients", clients), ("Action servers", servers)):
        print(f"{role}: {len(nodes)}")
        for node in nodes:
            print(f"    {ros_name(plan, node)}{suffix}")
    return 0


def cmd_action_send_goal(args: argparse.Namespace) -> int:
    from ..runtime import GoalStatus

    launch = _launch(args)
    typename = launch.actions().get(args.action)
    given = normalize_typename(args.type, "action")
    if typename is not None and given != typename:
        raise InspectError(f"{args.action} is a {typename}, not a {given}")
    goal = from_plain(launch.types, f"{given}_Goal", _values(args.values, "values"))
    print("Waiting for an action server to become available...\nSending goal:")
    print("".join(f"     {line}\n" for line in _dump(to_plain(launch.types, goal)).splitlines()))
    def show_feedback(message: Message) -> None:
        print("Feedback:")
        print("".join(f"    {line}\n" for line in _dump(to_plain(launch.types, message)).splitlines()), flush=True)

    ended = launch.send_goal(args.action, goal, feedback=show_feedback if args.feedback else None,
                             accepted=lambda goal_id: print(f"Goal accepted with ID: {goal_id}\n", flush=True))
    if ended is None:
        print("Goal was rejected.")
        return 1
    _goal_id, status, result = ended
    print("Result:")
    print("".join(f"    {line}\n" for line in _dump(to_plain(launch.types, result)).splitlines()))
    print(f"Goal finished with status: {GoalStatus(status).name}")
    return 0 if status == GoalStatus.SUCCEEDED else 1


def _parameter_kind(value: Any) -> str:
    if isinstance(value, bool):
        return "Boolean"
    if isinstance(value, int):
        return "Integer"
    if isinstance(value, float):
        return "Double"
    if isinstance(value, str):
        return "String"
    if isinstance(value, list):
        return "Array"
    return type(value).__name__


def cmd_param_list(args: argparse.Namespace) -> int:
    launch = _launch(args)
    nodes = [node_key(launch, args.node)] if args.node else sorted(
        n for n in launch.plan.nodes if launch.plan.runs_here(n))
    for node in nodes:
        parameters = launch.parameters(node)
        print(f"{ros_name(launch.plan, node)}:")
        for name in sorted(parameters):
            print(f"  {name}")
    return 0


def cmd_param_get(args: argparse.Namespace) -> int:
    launch = _launch(args)
    parameters = launch.parameters(node_key(launch, args.node))
    if args.name not in parameters:
        print("Parameter not set")
        return 1
    value = parameters[args.name]
    print(f"{_parameter_kind(value)} value is: {value}")
    return 0


def cmd_param_set(args: argparse.Namespace) -> int:
    launch = _launch(args)
    try:
        launch.set_parameter(node_key(launch, args.node), args.name, _values(args.value, "value"))
    except InspectError as exc:
        print(f"Setting parameter failed: {exc}")
        return 1
    print("Set parameter successful")
    return 0


def cmd_param_dump(args: argparse.Namespace) -> int:
    """ros2 param dump: the node's parameters as a parameter file (``ros__parameters``), which
    ``param load`` and a project's ``parameters:`` read back."""
    launch = _launch(args)
    node = node_key(launch, args.node)
    text = _dump({ros_name(launch.plan, node): {"ros__parameters": launch.parameters(node)}})
    if args.output_dir:
        out = Path(args.output_dir) / f"{ros_name(launch.plan, node).strip('/').replace('/', '__')}.yaml"
        out.write_text(text, encoding="utf-8")
        print(f"Saving to:  {out}")
    else:
        sys.stdout.write(text)
    return 0


def cmd_param_load(args: argparse.Namespace) -> int:
    """ros2 param load: set a node's parameters from a parameter file (its ``ros__parameters`` under the
    node's name, ``/**`` or the bare mapping)."""
    launch = _launch(args)
    node = node_key(launch, args.node)
    loaded = load_yaml(args.file, "parameter file", error=InspectError)
    name = ros_name(launch.plan, node)
    section = loaded.get(name, loaded.get(name.lstrip("/"), loaded.get("/**"))) if isinstance(loaded, dict) else None
    values = section.get("ros__parameters") if isinstance(section, dict) else None
    if not isinstance(values, dict):
        raise InspectError(f"{args.file}: no parameters for {name}: write them as {name}: {{ros__parameters: "
                           "{name: value}}} (or under /**)")
    failed = 0
    for key, value in values.items():
        try:
            launch.set_parameter(node, str(key), value)
            print(f"Set parameter {key} successful")
        except InspectError as exc:
            print(f"Set parameter {key} failed: {exc}")
            failed += 1
    return 1 if failed else 0


def cmd_bag_info(args: argparse.Namespace) -> int:
    from ..launch import recording_info

    print(recording_info(Path(args.bag)))
    return 0


# -- top --------------------------------------------------------------------------------------


def _top_rows(before: list[dict[str, Any]], after: list[dict[str, Any]]) -> dict[str, Any]:
    """Rates and CPU shares between two rounds of every process' counters."""
    earlier = {p["process"]: p for p in before}
    processes: list[dict[str, Any]] = []
    nodes: list[dict[str, Any]] = []
    topics: dict[str, dict[str, Any]] = {}
    gateways: list[dict[str, Any]] = []
    for now in after:
        then = earlier.get(now["process"])
        if then is None:
            continue
        span = max(now["time"] - then["time"], 1e-6)
        processes.append({"process": now["process"], "pid": now["pid"], "rss_mb": now["rss"] / 1e6,
                          "cpu_percent": 100.0 * (now["cpu_s"] - then["cpu_s"]) / span})
        for name, node in now["nodes"].items():
            old = then["nodes"].get(name, node)
            handled = node["handling"]
            p50 = max((h["p50_s"] for h in handled.values()), default=0.0)
            p99 = max((h["p99_s"] for h in handled.values()), default=0.0)
            nodes.append({"node": name, "process": now["process"], "alive": node["alive"],
                          "cpu_percent": 100.0 * (node["cpu_s"] - old["cpu_s"]) / span,
                          "callback_p50_ms": p50 * 1000.0, "callback_p99_ms": p99 * 1000.0})
            figures = node.get("figures") or {}
            for port, counts in figures.get("ports", {}).items():
                gateways.append({"gateway": name, "port": port, "messages": counts["messages"],
                                 "cycles_per_message": counts["cycles_per_message"],
                                 "us_per_message": counts["cycles_per_message"] / figures["clock_mhz"]})
        for name, topic in now["topics"].items():
            old_topic = then["topics"].get(name, topic)
            entry = topics.setdefault(name, {"topic": name, "type": topic["type"], "rate_hz": 0.0, "published": 0,
                                             "dropped": 0, "stalls": 0, "bytes_per_s": None})
            entry["rate_hz"] += (topic["published"] - old_topic["published"]) / span
            if topic.get("bytes"):  # counted where messages are serialized (shared memory); inproc copies nothing
                sent = topic["bytes"] - old_topic.get("bytes", 0)
                entry["bytes_per_s"] = (entry["bytes_per_s"] or 0.0) + sent / span
            for counter in ("published", "dropped", "stalls"):  # totals since the start
                entry[counter] += topic.get(counter, 0)
    return {"processes": processes, "nodes": nodes, "topics": sorted(topics.values(), key=lambda t: t["topic"]),
            "gateways": gateways}


def live_rates(session: str | None, project: str | None) -> tuple[Plan, dict[str, float]]:
    """A running launch's plan and each topic's rate over one second (``hetros graph --live``)."""
    launch = RunningLaunch.find(session, project)
    before = launch.stats()
    time.sleep(1.0)
    rows = _top_rows(before, launch.stats())
    return launch.plan, {t["topic"]: t["rate_hz"] for t in rows["topics"]}


def _format_top(rows: dict[str, Any], session: str) -> str:
    lines = [f"hetros top: launch {session}", "",
             f"{'PROCESS':<20} {'PID':>7} {'CPU%':>6} {'RSS MB':>8}"]
    lines += [f"{p['process']:<20} {p['pid']:>7} {p['cpu_percent']:>6.1f} {p['rss_mb']:>8.1f}"
              for p in rows["processes"]]
    if rows["silent"]:
        lines.append(f"(not answering: {', '.join(rows['silent'])})")
    lines += ["", f"{'NODE':<24} {'PROCESS':<16} {'CPU%':>6} {'CB p50 ms':>10} {'CB p99 ms':>10}"]
    lines += [f"{n['node']:<24} {n['process']:<16} {n['cpu_percent']:>6.1f} {n['callback_p50_ms']:>10.3f} "
              f"{n['callback_p99_ms']:>10.3f}" for n in rows["nodes"]]
    lines += ["", f"{'TOPIC':<32} {'RATE Hz':>9} {'BW':>11} {'SENT':>10} {'DROPS':>7} {'STALLS':>7}  TYPE"]
    lines += [f"{t['topic']:<32} {t['rate_hz']:>9.1f} "
              f"{'-' if t['bytes_per_s'] is None else _bytes(t['bytes_per_s']) + '/s':>11} {t['published']:>10} "
              f"{t['dropped']:>7} {t['stalls']:>7}  {t['type']}" for t in rows["topics"]]
    if rows["gateways"]:
        lines += ["", f"{'GATEWAY PORT':<48} {'MESSAGES':>9} {'CYCLES/MSG':>11} {'US/MSG':>8}"]
        lines += [f"{g['port']:<48} {g['messages']:>9} {g['cycles_per_message']:>11.0f} {g['us_per_message']:>8.2f}"
                  for g in rows["gateways"]]
    return "\n".join(lines)


def cmd_top(args: argparse.Namespace) -> int:
    launch = _launch(args)
    before = launch.stats()
    rounds = 0
    while True:
        time.sleep(args.interval)
        after = launch.stats()
        if not after:
            raise InspectError(f"launch {launch.record.session} has ended")
        rows = _top_rows(before, after)
        answered = {p["process"] for p in after}
        rows["silent"] = [p for p in launch.processes() if p not in answered]  # starting, or stuck
        if args.json:
            print(json.dumps(rows), flush=True)
        else:
            sys.stdout.write(("\x1b[H\x1b[2J" if sys.stdout.isatty() else "") + _format_top(rows, launch.record.session)
                             + "\n")
            sys.stdout.flush()
        before = after
        rounds += 1
        if args.once or (args.count and rounds >= args.count):
            return 0


# -- log ----------------------------------------------------------------------------------------

def cmd_log(args: argparse.Namespace) -> int:
    launch = _launch(args)
    logs = LaunchLogs(launch.folder)
    nodes = {node_key(launch, name) for name in args.node or []}
    while True:
        for record in logs.new_records():
            if not nodes or record.name in nodes:
                print(record.text, flush=True)
        if not args.follow or not launch.folder.exists():
            return 0
        time.sleep(0.2)


# -- record, play ----------------------------------------------------------------------------------


def cmd_record(args: argparse.Namespace) -> int:
    from ..launch import record, recordable

    launch = _launch(args)
    if not args.all and not args.topics:
        raise InspectError("name the topics to record (-t /a /b) or record them all (-a)")
    topics = recordable(launch, None if args.all else args.topics)
    out = Path(args.output or time.strftime("rosbag2_%Y_%m_%d-%H_%M_%S.mcap"))
    print(f"recording {', '.join(topics)} of launch {launch.record.session} into {out}; Ctrl-C stops",
          file=sys.stderr)
    # Ctrl-C ends the recording with its file whole (record closes it on the way out)
    compression = "" if args.compression_mode == "none" else args.compression_mode
    print(record(launch, topics, out, duration=args.duration, compression=compression).describe())
    return 0


def cmd_play(args: argparse.Namespace) -> int:
    from ..launch import describe_played, play

    overrides = Path(args.qos_profile_overrides_path) if args.qos_profile_overrides_path else None
    if args.launch:
        from ..launch import play_launching

        return play_launching(Path(args.bag), Path(args.launch), rate=args.rate, clock=args.clock,
                              lockstep=args.lockstep, topics=args.topics, start_offset=args.start_offset,
                              remap=_remaps(args.remap), qos_overrides=overrides)
    launch = _launch(args)
    while True:
        counts = play(launch, Path(args.bag), rate=args.rate, loop=False, clock=args.clock, lockstep=args.lockstep,
                      topics=args.topics, start_offset=args.start_offset, remap=_remaps(args.remap),
                      qos_overrides=overrides)
        print(describe_played(counts))
        if not args.loop:
            return 0


def _remaps(pairs: list[str] | None) -> dict[str, str]:
    """``--remap old:=new ...`` as a mapping, each checked."""
    found: dict[str, str] = {}
    for pair in pairs or []:
        old, sep, new = pair.partition(":=")
        if not sep or not old.startswith("/") or not new.startswith("/"):
            raise InspectError(f"--remap takes /old:=/new, not {pair!r}")
        found[old] = new
    return found


def cmd_foxglove(args: argparse.Namespace) -> int:
    from ..launch import FoxgloveView

    launch = _launch(args)
    view = FoxgloveView(launch, host=args.host, port=args.port, max_rate=args.max_rate, backlog=args.backlog)
    print(f"serving launch {launch.record.session} ({launch.record.project}) to Foxglove at "
          f"ws://{args.host}:{view.port}; Ctrl-C stops", flush=True)
    try:
        while launch.folder.exists():
            time.sleep(0.5)
    finally:
        view.close()
    print("the launch ended")
    return 0


# -- the parser ---------------------------------------------------------------------------------


def _which(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--session", help="the launch's session (hetros ps); default: the only one running")
    parser.add_argument("--project", help="the launch of this project file (or folder)")


def _request_parser(group: Any, verb: str, what: str, description: str,
                    function: Callable[[argparse.Namespace], int]) -> None:
    parser = group.add_parser(verb, help=description)
    parser.add_argument(what)
    parser.add_argument("type")
    parser.add_argument("values", nargs="?", default="{}", help="YAML field values: \"{a: 1, b: 2}\"")
    if what == "action":
        parser.add_argument("-f", "--feedback", action="store_true", help="print each feedback as it comes")
    parser.set_defaults(func=function)


def _echo_options(p: argparse.ArgumentParser, what: str) -> None:
    """The options ``topic echo`` and ``service echo`` share, as ros2's echo verbs take them."""
    p.add_argument("--once", action="store_true", help=f"print one of the {what} and exit")
    p.add_argument("-n", "--times", type=numbers.count, default=0, help=f"print this many {what} and exit")
    p.add_argument("--no-arr", action="store_true", help="print arrays' types and lengths instead of their values")
    p.add_argument("--no-str", action="store_true", help="print strings' lengths instead of their values")
    p.add_argument("-l", "--truncate-length", type=numbers.count, default=DEFAULT_TRUNCATE_LENGTH,
                   help="cut arrays and strings at this length (default %(default)s)")
    p.add_argument("-f", "--full-length", action="store_true", help="do not cut arrays and strings")
    p.add_argument("--flow-style", action="store_true")
    p.add_argument("--duration", type=numbers.seconds, help="stop after this many seconds")


def add_commands(sub: Any) -> None:
    """The introspection commands, added to ``hetros``'s subcommands."""
    topic = sub.add_parser("topic", help="topics of a running launch (ros2 topic)").add_subparsers(
        dest="topic_command", required=True)
    p = topic.add_parser("list", help="the launch's topics")
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("--include-hidden-topics", action="store_true", help="also actions' topics")
    p.set_defaults(func=cmd_topic_list)
    p = topic.add_parser("info", help="a topic's type and endpoint counts")
    p.add_argument("topic")
    p.add_argument("-v", "--verbose", action="store_true", help="each endpoint: node, target, transports, QoS")
    p.set_defaults(func=cmd_topic_info)
    p = topic.add_parser("type", help="a topic's type")
    p.add_argument("topic")
    p.set_defaults(func=cmd_topic_type)
    p = topic.add_parser("find", help="the topics of a type")
    p.add_argument("type")
    p.add_argument("--include-hidden-topics", action="store_true", help="also actions' topics")
    p.set_defaults(func=cmd_topic_find)
    p = topic.add_parser("echo", help="print a topic's messages as YAML")
    p.add_argument("topic")
    _echo_options(p, "messages")
    p.add_argument("--field", help="print one field (header.stamp)")
    p.add_argument("--lost-messages", action="store_true", help="report messages the tap dropped")
    p.set_defaults(func=cmd_topic_echo)
    for verb, function, window, what in (("hz", cmd_topic_hz, HZ_WINDOW, "publishing rate"),
                                         ("bw", cmd_topic_bw, BW_WINDOW, "bandwidth"),
                                         ("delay", cmd_topic_delay, HZ_WINDOW, "delay from header stamp")):
        p = topic.add_parser(verb, help=f"a topic's {what}, printed every second")
        p.add_argument("topic")
        p.add_argument("-w", "--window", type=numbers.positive_count, default=window,
                       help="messages per figure (default %(default)s)")
        p.add_argument("--duration", type=numbers.seconds, help="stop after this many seconds")
        p.set_defaults(func=function)
    p = topic.add_parser("pub", help="publish a message to a topic's subscribers")
    p.add_argument("topic")
    p.add_argument("type")
    p.add_argument("values", nargs="?", default="{}", help="YAML field values: \"{data: hello}\"")
    p.add_argument("-1", "--once", action="store_true", help="publish one message and exit")
    p.add_argument("-t", "--times", type=numbers.count, default=0, help="publish this many messages and exit")
    p.add_argument("-r", "--rate", type=numbers.hertz, default=1.0, help="messages per second (default 1)")
    p.set_defaults(func=cmd_topic_pub)
    node = sub.add_parser("node", help="nodes of a running launch (ros2 node)").add_subparsers(
        dest="node_command", required=True)
    p = node.add_parser("list")
    p.set_defaults(func=cmd_node_list)
    p = node.add_parser("info")
    p.add_argument("node")
    p.add_argument("--include-hidden", action="store_true", help="also actions' services and topics")
    p.set_defaults(func=cmd_node_info)
    groups = {}
    for word, verb, list_function, request_function, description in (
            ("service", "call", cmd_service_list, cmd_service_call, "call a service and print the response"),
            ("action", "send_goal", cmd_action_list, cmd_action_send_goal, "send a goal and print its result")):
        group = groups[word] = sub.add_parser(word, help=f"{word}s of a running launch (ros2 {word})").add_subparsers(
            dest=f"{word}_command", required=True)
        p = group.add_parser("list")
        p.add_argument("-t", "--show-types", action="store_true")
        p.set_defaults(func=list_function)
        _request_parser(group, verb, word, description, request_function)
    p = groups["service"].add_parser("type", help="a service's type")
    p.add_argument("service")
    p.set_defaults(func=cmd_service_type)
    p = groups["service"].add_parser("echo", help="each call of a service as its events (ros2 service echo)")
    p.add_argument("service")
    p.add_argument("service_type", nargs="?", help="its type, checked (pkg/srv/Type)")
    _echo_options(p, "events")
    p.set_defaults(func=cmd_service_echo)
    p = groups["service"].add_parser("find", help="the services of a type")
    p.add_argument("type")
    p.set_defaults(func=cmd_service_find)
    p = groups["action"].add_parser("info", help="an action's clients and servers")
    p.add_argument("action")
    p.add_argument("-t", "--show-types", action="store_true")
    p.set_defaults(func=cmd_action_info)
    lifecycle = sub.add_parser("lifecycle", help="managed nodes of a running launch (ros2 lifecycle)").add_subparsers(
        dest="lifecycle_command", required=True)
    p = lifecycle.add_parser("nodes", help="the managed nodes")
    p.set_defaults(func=cmd_lifecycle_nodes)
    p = lifecycle.add_parser("get", help="a managed node's state (every one's without a node)")
    p.add_argument("node", nargs="?")
    p.set_defaults(func=cmd_lifecycle_get)
    p = lifecycle.add_parser("list", help="the transitions available from a managed node's state")
    p.add_argument("node")
    p.add_argument("-a", "--all", action="store_true", help="every transition of the state machine")
    p.set_defaults(func=cmd_lifecycle_list)
    p = lifecycle.add_parser("set", help="take a transition (configure, activate, deactivate, cleanup, shutdown)")
    p.add_argument("node")
    p.add_argument("transition", help="its label or id")
    p.set_defaults(func=cmd_lifecycle_set)
    param = sub.add_parser("param", help="parameters of a running launch's nodes (ros2 param)").add_subparsers(
        dest="param_command", required=True)
    p = param.add_parser("list")
    p.add_argument("node", nargs="?")
    p.set_defaults(func=cmd_param_list)
    p = param.add_parser("get")
    p.add_argument("node")
    p.add_argument("name")
    p.set_defaults(func=cmd_param_get)
    p = param.add_parser("set")
    p.add_argument("node")
    p.add_argument("name")
    p.add_argument("value", help="YAML: 5, 2.5, true, hello, [1, 2]")
    p.set_defaults(func=cmd_param_set)
    p = param.add_parser("dump", help="a node's parameters as a parameter file (ros__parameters)")
    p.add_argument("node")
    p.add_argument("--output-dir", help="write <node>.yaml there instead of printing it")
    p.set_defaults(func=cmd_param_dump)
    p = param.add_parser("load", help="set a node's parameters from a parameter file")
    p.add_argument("node")
    p.add_argument("file")
    p.set_defaults(func=cmd_param_load)
    p = sub.add_parser("top", help="a running launch's live figures: CPU, memory, callback times, topic rates")
    p.add_argument("--json", action="store_true", help="one JSON object per interval, for machines")
    p.add_argument("--interval", type=numbers.positive_seconds, default=1.0, help="seconds between figures (default 1)")
    p.add_argument("--once", action="store_true", help="print one round and exit")
    p.add_argument("-n", "--count", type=numbers.count, default=0, help="print this many rounds and exit")
    p.set_defaults(func=cmd_top)
    p = sub.add_parser("log", help="the log lines of a running launch's nodes, every process merged in time")
    p.add_argument("-f", "--follow", action="store_true", help="keep printing new lines until the launch ends")
    p.add_argument("--node", action="append", help="only this node's lines (repeatable)")
    p.set_defaults(func=cmd_log)
    p = sub.add_parser("foxglove", help="serve a running launch to Foxglove (its WebSocket protocol)")
    p.add_argument("--host", default="127.0.0.1", help="interface to listen on (default 127.0.0.1 only)")
    p.add_argument("--port", type=numbers.port, default=8765, help="default %(default)s; 0 picks a free one")
    p.add_argument("--max-rate", type=_rate, default=30.0,
                   help="messages per second per topic at most (default %(default)s); never slows a publisher")
    p.add_argument("--backlog", type=numbers.positive_count, default=8,
                   help="messages kept per client that does not read (default %(default)s; the oldest goes first)")
    p.set_defaults(func=cmd_foxglove)
    p = sub.add_parser("record", help="record a running launch's topics into MCAP (ros2 bag record)")
    p.add_argument("-t", "--topics", nargs="+", help="the topics to record")
    p.add_argument("-a", "--all", action="store_true", help="every topic this machine sees")
    p.add_argument("-o", "--output", help="run.mcap (one file), or a folder for a rosbag2 bag")
    p.add_argument("--duration", type=numbers.seconds, help="stop after this many seconds")
    p.add_argument("--compression-mode", choices=["none", "file", "message"], default="none",
                   help="compress each file whole or each message (a rosbag2 folder only; default none)")
    p.add_argument("--compression-format", choices=["zstd"], default="zstd", help="rosbag2's: zstd")
    p.set_defaults(func=cmd_record)
    bag = sub.add_parser("bag", help="recordings (ros2 bag)").add_subparsers(dest="bag_command", required=True)
    p = bag.add_parser("info", help="a recording's files, size, duration, and per topic its type and count")
    p.add_argument("bag", help="a rosbag2 folder (MCAP or sqlite3 storage), or an .mcap, .db3 or ROS 1 .bag file")
    p.set_defaults(func=cmd_bag_info)
    p = sub.add_parser("play", help="play a recording into a running launch (ros2 bag play)")
    p.add_argument("bag", help="a rosbag2 folder (MCAP or sqlite3 storage), or an .mcap, .db3 or ROS 1 .bag file")
    p.add_argument("-r", "--rate", type=numbers.speed, default=1.0, help="speed factor (default 1)")
    p.add_argument("-l", "--loop", action="store_true", help="play again and again")
    p.add_argument("--clock", action="store_true", help="publish the recording's time on /clock (use_sim_time)")
    p.add_argument("--lockstep", action="store_true",
                   help="deliver each message only when its consumers finished the previous one, in the "
                        "recording's time: the same outputs on every replay and every mapping")
    p.add_argument("--topics", nargs="+", help="play only these topics")
    p.add_argument("--start-offset", type=numbers.seconds, default=0.0, help="skip this many seconds of the recording")
    p.add_argument("--remap", nargs="+", metavar="OLD:=NEW", help="play a recorded topic onto another")
    p.add_argument("--qos-profile-overrides-path", metavar="FILE", help="rosbag2's QoS override file (topic -> "
                   "reliability, history, depth, durability, deadline, lifespan, ...): with --launch the QoS the "
                   "topics are launched with; into a running launch, checked against its QoS")
    p.add_argument("--launch", metavar="PROJECT", help="launch the part of this project that consumes the recording "
                   "(its nodes that only publish recorded topics stay out), play into it, then stop it")
    p.set_defaults(func=cmd_play)
    for group in (topic, node, groups["service"], groups["action"], lifecycle, param):
        for parser in group.choices.values():
            _which(parser)
    for name in ("top", "log", "foxglove", "record", "play"):
        _which(sub.choices[name])
    from ._tf import add_commands as add_tf_commands

    add_tf_commands(sub, _which)


def _rate(text: str) -> float:
    """``--max-rate``: checked here, so that a NaN or a vanishing rate never reaches a publisher."""
    from ..runtime import check_rate

    try:
        return check_rate(float(text), "--max-rate")
    except (ValueError, Error) as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None

