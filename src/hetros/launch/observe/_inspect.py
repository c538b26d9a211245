"""The looking side of ``launch._control``: find a running launch and ask its processes.

The plan the launcher wrote into its private session folder says exactly which topics,
nodes and services there are and which process to ask about each; the processes' control
sockets answer for what only a running process knows (messages, rates, parameters).
"""

from __future__ import annotations

import contextlib
import difflib
import queue
import socket
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

from ..._errors import InputFileError, InspectError, LaunchError
from ..._files import load_yaml, read_text
from ..._signals import next_item
from ...msg import Message, TypeRegistry, registry
from ...plan import PARAMETER_SERVICES, Plan
from ...runtime import EVENT_TOPIC_SUFFIX
from ...transport import MessageCodec
from ..launcher._registry import LaunchRecord, registry_folder, running
from ._control import receive_frame, send_frame, short_path


@dataclass(frozen=True)
class TapEvent:
    """One message seen by a tap: when (wall ns), what (encoded CDR, or None for a meta tap), how
    big, its header stamp (ns, when it has one), and how many the tap dropped before it."""

    time_ns: int
    data: bytes | None
    size: int
    stamp: int | None
    dropped: int
    process: str = ""  # the process whose tap saw it


def choose(records: list[LaunchRecord], session: str | None, project: str | None) -> LaunchRecord:
    """The launch a command means: the one with ``session``, or whose project file is ``project``,
    or the only one running."""
    if session:
        chosen = [r for r in records if r.session == session]
        what = f"session {session}"
    elif project:
        if "\x00" in project:
            raise InspectError(f"--project {project!r} is not a path (it holds a NUL character)")
        path = Path(project).resolve()
        if path.is_file():
            name = _project_name(path)
            chosen = [r for r in records if Path(r.root).resolve() == path.parent and r.project == name]
        else:
            chosen = [r for r in records if Path(r.root).resolve() == path or r.project == project]
        what = f"project {project}"
    else:
        chosen, what = records, "any project"
    if len(chosen) == 1:
        return chosen[0]
    if not chosen:
        listing = ", ".join(f"{r.session} ({r.project})" for r in records) or "none"
        raise InspectError(f"no running hetros launch of {what} (as this user, on this machine; running: {listing}); "
                           "start one with `hetros launch`, or see `hetros ps`")
    listing = "\n".join(f"  {r.session}  {r.project}  ({r.root})" for r in chosen)
    raise InspectError(f"{len(chosen)} launches of {what} are running; name one with --session:\n{listing}")


def _project_name(path: Path) -> str:
    """The ``name:`` a project file gives its graph (what ``hetros ps`` lists)."""
    data = load_yaml(path, "--project file", error=InspectError)
    name = data.get("name") if isinstance(data, dict) else None
    if not isinstance(name, str):
        raise InspectError(f"--project {path}: the file has no name: (is it a hetros project file?)")
    return name


# a plan of a few hundred nodes is a few hundred kB
PLAN_LIMIT = 64 << 20


class RunningLaunch:
    """One running launch, as seen from another terminal of the same user."""

    def __init__(self, record: LaunchRecord) -> None:
        self.record = record
        self.folder = registry_folder() / record.session
        path = self.folder / "plan.json"
        try:
            self.plan = Plan.from_json(read_text(path, "launch plan", limit=PLAN_LIMIT), str(path))
        except InputFileError as exc:
            raise InspectError(f"launch {record.session} has no readable plan ({exc}); it is ending, or it "
                               "was started by an older hetros") from None
        self.types: TypeRegistry = registry()
        for folder in self.plan.message_paths:
            self.types.load_folder(Path(folder))

    @classmethod
    def find(cls, session: str | None = None, project: str | None = None) -> RunningLaunch:
        return cls(choose(running(), session, project))

    # -- talking to a process ----------------------------------------------------------------

    def connect(self, process: str, request: dict[str, Any], payload: bytes = b"",
                timeout: float | None = 10.0) -> socket.socket:
        path = self.folder / f"{process}.sock"
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.settimeout(timeout)
        try:
            with short_path(path) as name:
                sock.connect(name)
            send_frame(sock, request, payload)
        except (FileNotFoundError, ConnectionRefusedError):
            sock.close()
            raise InspectError(f"process {process} of launch {self.record.session} has no control socket "
                               f"({path}): it is starting, or it has ended") from None
        except PermissionError:
            sock.close()
            raise InspectError(f"{path}: permission denied; only the user who started a launch can look "
                               "inside it") from None
        except OSError as exc:
            sock.close()
            raise InspectError(f"process {process} of launch {self.record.session} did not answer ({exc})") from None
        return sock

    def ask(self, process: str, request: dict[str, Any], payload: bytes = b"",
            timeout: float = 15.0) -> tuple[dict[str, Any], bytes]:
        with self.connect(process, request, payload, timeout) as sock:
            try:
                answer, data = receive_frame(sock)
            except TimeoutError:
                raise InspectError(f"process {process} did not answer {request.get('op')} within {timeout:g} s") \
                    from None
        if "error" in answer:
            raise InspectError(f"{process}: {answer['error']}")
        return answer, data

    # -- what the plan says -------------------------------------------------------------------

    def processes(self) -> list[str]:
        """This host's processes of the launch that run nodes (the launcher's only when it hosts some)."""
        local = sorted({self.plan.process_of(n) for n in self.plan.nodes if self.plan.runs_here(n)})
        return local

    def topic(self, name: str) -> str:
        """The type of topic ``name``; InspectError naming the topics when there is no such topic."""
        channel = self.plan.channels.get(name)
        if channel is None or channel.kind != "topic":
            known = ", ".join(sorted(n for n, c in self.plan.channels.items() if c.kind == "topic"))
            raise InspectError(f"launch {self.record.session} has no topic {name} (its topics: {known})")
        return channel.type

    def codec(self, typename: str) -> MessageCodec:
        return MessageCodec(self.types, typename)

    # -- looks -------------------------------------------------------------------------------

    def tap(self, topic: str, *, data: bool = True, max_rate: float = 0.0) -> Iterator[TapEvent | None]:
        """Messages on ``topic`` as they are published, from every process that publishes it here;
        None every half second when nothing came (so a caller can end on time)."""
        for _topic, event in self.tap_many([topic], data=data, max_rate=max_rate):
            yield event

    def tap_many(self, topics: list[str], *, data: bool = True, max_rate: float = 0.0,
                 attached: Callable[[], None] = lambda: None) -> Iterator[tuple[str, TapEvent | None]]:
        """``(topic, message)`` on any of ``topics``, merged in the order they arrive here; ``(topic, None)``
        every half second a tap saw nothing. ``attached()`` is called once every tap is in place."""
        for topic in topics:
            self.topic(topic)
            if not self.plan.tap_sites(topic)[1]:
                where = ", ".join(sorted({self.plan.host_of(n) for n in self.plan.channels[topic].publishers}))
                raise InspectError(f"{topic} is neither published nor subscribed on this machine (host "
                                   f"{self.record.host or '-'}); look at it on {where or '?'}")
        sites = [(topic, process) for topic in topics for process in self.plan.tap_sites(topic)[1]]
        yield from self._tap_sites(sites, data=data, max_rate=max_rate, attached=attached)

    def tap_service(self, service: str) -> Iterator[TapEvent | None]:
        """The events of ``service``'s calls (``<srv>_Event``, ROS 2's introspection) from every process
        here that serves or calls it; None every half second when nothing came."""
        self.server_of(service)
        plan = self.plan
        processes = sorted({plan.process_of(name) for name, spec in plan.nodes.items()
                            if (service in spec.services or service in spec.clients) and plan.runs_here(name)
                            and not plan.in_hardware(name)})
        if not processes:
            raise InspectError(f"neither the server nor a client of {service} runs in software on this machine")
        for _topic, event in self._tap_sites([(service + EVENT_TOPIC_SUFFIX, p) for p in processes], data=True):
            yield event

    def _tap_sites(self, sites: list[tuple[str, str]], *, data: bool, max_rate: float = 0.0,
                   attached: Callable[[], None] = lambda: None) -> Iterator[tuple[str, TapEvent | None]]:
        events: queue.Queue[tuple[str, TapEvent | None] | Exception] = queue.Queue()
        sockets = []
        try:
            for topic, process in sites:
                sock = self.connect(process, {"op": "tap", "topic": topic, "data": data,
                                              "max_rate": max_rate}, timeout=None)
                sockets.append(sock)
                answer, _ = receive_frame(sock)
                if "error" in answer:
                    raise InspectError(f"{process}: {answer['error']}")
                threading.Thread(target=_pump, args=(sock, process, topic, events), daemon=True).start()
            attached()
            while True:
                event = next_item(events)
                if isinstance(event, Exception):
                    raise event
                yield event
        finally:
            for sock in sockets:
                with contextlib.suppress(OSError):
                    sock.shutdown(socket.SHUT_RDWR)
                sock.close()

    def decode(self, typename: str, data: bytes) -> Message:
        return self.codec(typename).decode(memoryview(data))

    def publish(self, topic: str, message: Message, *, wait: float = 0.0) -> list[str]:
        """Deliver ``message`` to every subscription of ``topic`` running here; the nodes reached.
        With ``wait``, return only once each has finished with it (its callback returned, or its
        take loop took the next message), at most ``wait`` seconds."""
        return self.publish_bytes(topic, bytes(self.codec(self.topic(topic)).encode(message)), wait=wait)

    def publish_bytes(self, topic: str, data: bytes, *, wait: float = 0.0) -> list[str]:
        """:meth:`publish` of a message already encoded (CDR, as a recording holds it)."""
        typename = self.topic(topic)
        channel = self.plan.channels[topic]
        processes = sorted({self.plan.process_of(n) for n in channel.subscribers if self.plan.runs_here(n)})
        reached: list[str] = []
        for process in processes:
            answer, _ = self.ask(process, {"op": "pub", "topic": topic, "type": typename, "wait": wait}, data,
                                 timeout=wait + 15.0)
            reached += answer["subscriptions"]
        return reached

    def settle(self, topic: str, seconds: float) -> None:
        """Wait until every subscription of ``topic`` has handled the messages published into it from here."""
        channel = self.plan.channels[topic]
        for process in sorted({self.plan.process_of(n) for n in channel.subscribers if self.plan.runs_here(n)}):
            self.ask(process, {"op": "settle", "topic": topic, "wait": seconds}, timeout=seconds + 15.0)

    def server_of(self, service: str) -> tuple[str, str]:
        """(node, service type) of the node serving ``service``."""
        for name, node in self.plan.nodes.items():
            if service in node.services and not service.startswith(tuple(f"{a}/_action/" for a in node.actions)):
                if self.plan.in_hardware(name):
                    raise InspectError(f"{service} is served in hardware (node {name} on fpga target {node.target}); "
                                       "the command line calls software servers: call it from a node")
                return name, node.services[service]
        if (parameters := self.plan.parameter_servers().get(service)) is not None:
            return parameters
        known = self.services()
        near = difflib.get_close_matches(service, known, n=3)
        hint = f"did you mean {' or '.join(near)}?" if near else f"its services: {', '.join(known) or 'none'}"
        raise InspectError(f"launch {self.record.session} has no service {service} ({hint})")

    def services(self) -> list[str]:
        """Every service of the launch, each node's parameter services among them (as ``ros2 service list``)."""
        return sorted({s for node in self.plan.nodes.values() for s in node.services if "/_action/" not in s}
                      | set(self.plan.parameter_servers()))

    def call(self, service: str, request: Message, timeout: float = 10.0) -> Message:
        node, typename = self.server_of(service)
        return self._call_at(self.plan.process_of(node), service, typename, request, timeout)

    def _call_at(self, process: str, service: str, typename: str, request: Message, timeout: float = 10.0) -> Message:
        _, data = self.ask(process, {"op": "call", "service": service, "timeout": timeout},
                           bytes(self.codec(f"{typename}_Request").encode(request)), timeout + 5.0)
        return self.decode(f"{typename}_Response", data)

    def live_nodes(self) -> dict[str, str]:
        """Full ROS name -> process of every node alive on this machine: the plan's, and the ones their
        code made beside them (rclpy's Node('other') in the same main); a silent process is left out."""
        found: dict[str, str] = {}
        for process in self.processes():
            with contextlib.suppress(InspectError, LaunchError):
                answer = self.ask(process, {"op": "nodes"}, timeout=5.0)[0]
                for name in answer.get("nodes", []):
                    if isinstance(name, str):
                        found.setdefault(name, process)
        return found

    def _parameter_node(self, node: str) -> tuple[str, str]:
        """(process, full ROS name) of a node by its plan key, or by the full name of a node the code made."""
        if node in self.plan.nodes:
            return self.node_process(node), self.plan.full_name(node)
        process = self.live_nodes().get(node)
        if process is None:
            known = ", ".join(sorted(self.plan.nodes))
            raise InspectError(f"launch {self.record.session} has no node {node} (its nodes: {known})")
        return process, node

    def actions(self) -> dict[str, str]:
        """Action name -> type, of every action served in the launch."""
        return {a: t for node in self.plan.nodes.values() for a, t in node.actions.items()}

    def send_goal(self, action: str, goal: Message, timeout: float = 600.0,
                  feedback: Callable[[Message], None] | None = None,
                  accepted: Callable[[str], None] | None = None) -> tuple[str, int, Message] | None:
        """Send ``goal`` to ``action``'s server and wait for the end: (goal id, status, result), or None
        when the server rejected it. ``feedback(message)`` hears each feedback the goal gets meanwhile;
        ``accepted(goal_id)`` is told as soon as the server accepted it."""
        server = next((n for n, spec in self.plan.nodes.items() if action in spec.actions), None)
        if server is None:
            known = ", ".join(sorted(self.actions())) or "none"
            raise InspectError(f"launch {self.record.session} has no action {action} (its actions: {known})")
        typename = self.plan.nodes[server].actions[action]
        request = {"op": "send_goal", "action": action, "timeout": timeout, "feedback": feedback is not None}
        with self.connect(self.node_process(server), request, bytes(self.codec(f"{typename}_Goal").encode(goal)),
                          timeout=timeout + 30.0) as sock:
            answer, _ = receive_frame(sock)
            if "error" in answer:
                raise InspectError(answer["error"])
            if not answer["accepted"]:
                return None
            goal_id = str(answer["goal_id"])
            if accepted is not None:
                accepted(goal_id)
            ended, data = receive_frame(sock)
            while ended.get("feedback") and feedback is not None:
                feedback(self.decode(f"{typename}_Feedback", data))
                ended, data = receive_frame(sock)
        if "error" in ended:
            raise InspectError(ended["error"])
        return goal_id, int(ended["status"]), self.decode(f"{typename}_Result", data)

    def node_process(self, node: str) -> str:
        if node not in self.plan.nodes:
            known = ", ".join(sorted(self.plan.nodes))
            raise InspectError(f"launch {self.record.session} has no node {node} (its nodes: {known})")
        if not self.plan.runs_here(node):
            raise InspectError(f"node {node} does not run in a process of this machine (it runs in hardware or on "
                               f"host {self.plan.host_of(node) or '-'})")
        return self.plan.process_of(node)

    def parameters(self, node: str) -> dict[str, Any]:
        """``node``'s parameters, name -> value, read through its parameter services."""
        from ...interfaces.rcl_interfaces.srv import GetParameters, ListParameters
        from ...runtime import from_value_message

        process, base = self._parameter_node(node)
        listed: Any = self._call_at(process, f"{base}/list_parameters", PARAMETER_SERVICES["list_parameters"],
                                    ListParameters.Request())
        names = list(listed.result.names)
        values = cast(Any, self._call_at(process, f"{base}/get_parameters", PARAMETER_SERVICES["get_parameters"],
                                         GetParameters.Request(names=names))).values
        return {name: from_value_message(value) for name, value in zip(names, values, strict=True)}

    def set_parameter(self, node: str, name: str, value: Any) -> None:
        """Set ``node``'s parameter ``name`` through its parameter service: its callbacks (rclpy's) may
        refuse it, and the reason comes back as an :class:`InspectError`."""
        from ...interfaces.rcl_interfaces.msg import Parameter
        from ...interfaces.rcl_interfaces.srv import SetParameters
        from ...runtime import to_value_message

        process, base = self._parameter_node(node)
        request = SetParameters.Request(parameters=[Parameter(name=name, value=to_value_message(value))])
        result = cast(Any, self._call_at(process, f"{base}/set_parameters", PARAMETER_SERVICES["set_parameters"],
                                         request)).results[0]
        if not result.successful:
            raise InspectError(result.reason or f"node {node} refused {name}={value!r} without a reason")

    def stats(self) -> list[dict[str, Any]]:
        """Each process' counters (``hetros top``); a process that does not answer is left out."""
        found = []
        for process in self.processes():
            with contextlib.suppress(InspectError, LaunchError):
                found.append(self.ask(process, {"op": "stats"}, timeout=5.0)[0])
        return found


def _pump(sock: socket.socket, process: str, topic: str,
          events: queue.Queue[tuple[str, TapEvent | None] | Exception]) -> None:
    try:
        while True:
            header, payload = receive_frame(sock)
            if header.get("idle"):
                events.put((topic, None))
                continue
            events.put((topic, TapEvent(int(header["t"]), payload if payload else None,
                                        int(header.get("size", len(payload))), header.get("stamp"),
                                        int(header.get("dropped", 0)), process)))
    except (OSError, InspectError) as exc:
        events.put(InspectError(f"the tap of {topic} in {process} ended: {exc}"))
