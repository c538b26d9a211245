"""The gateway node of an fpga target: its hardware co-simulated, its topics and services in the graph.

The planner gives each fpga target whose topics or services cross to software a gateway node
(``plan.gateway_node``) in a process of the target's own. That node builds the target's top
module and has Verilator compile it (``hetros.hw.sim._cosim``) while the process starts, then
moves messages between the graph and the simulated ports: what software publishes to the
hardware arrives through the gateway's ordinary subscriptions (shared memory from the other
processes of the host) and is pushed into the top's ``s_axis`` port as its CDR body; what
the hardware publishes comes out of an ``m_axis`` port and is published as an ordinary
message. A hardware server takes each request's body and answers in order; the gateway keeps
who asked and answers each client on its reply channel. Software nodes cannot tell a
hardware peer from a software one.

Hardware TCPROS (Sugata et al.): a topic the target's hardware frames for ROS 1 itself
(``plan.TargetPlan.ros1_export``/``ros1_import``) has a port of TCPROS frames; the gateway is then
a ROS 1 node of its own (``/<project>_<target>``), does the registration (master, ``requestTopic``,
connection headers) and moves each frame between the port and the sockets unchanged.

Each port moves on its own, as on a board. Reliable topics stay lossless across the gateway: it
takes from a subscription only while the port's queue has room, so a full hardware side fills the
subscription's FIFO and then blocks the software publisher, as any slow subscriber would. At an
output it publishes only what a subscriber has room for (``Publisher.has_room``): a full one
leaves its messages in the simulator, whose output then takes TREADY low at that port alone (the
AXI4-Stream monitor checks the node under it), and the rest of the design runs on. The gateway's
one thread never waits on a subscriber, so one slow reader cannot stop the target's clock.
"""

from __future__ import annotations

import os
import threading
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..._errors import HardwareError, SerializationError
from ..._log import get_logger
from ...hw import IDLE, SIMULATOR_NICE_VARIABLE, GatewayPort, SimulatedTop, TargetSimulation, VerilatedTop
from ...msg import TypeRegistry
from ...plan import Plan
from ...runtime import Node, Replies, header_stamp
from ...transport.tcpros import Ros1Peer, Ros1Type, receive_frames

log = get_logger("hetros.cosim")

# seconds between looks at an output whose subscriber was full (taking does not wake the gateway)
_HELD_POLL = 0.002
# messages a gateway keeps queued at an input port: enough that the hardware never waits for Python
# between two messages, few enough that back-pressure reaches the publisher early
_QUEUED = 2
# cycles a run may take before Python looks at the graph again, and quiet cycles after which a design
# whose inputs are empty counts as idle (the gateway then sleeps until software publishes): few right after
# a message went in or out (the next one is likely on its way), more after a sleep that nothing woke
_CHUNK = 2_000_000
_QUIET_AFTER_TRAFFIC = 256
_IDLE_CYCLES = 20_000
# while more messages went into the hardware than came out, it is working (a sort, a frame's flush) even
# with its ports quiet: the clock runs on, up to this many cycles since a message last went in or out
_IN_FLIGHT_CYCLES = 50_000_000
# simulations built while the process started (``gateway.prepare``), by gateway node
_PREPARED: dict[str, TargetSimulation] = {}


def _prepare(plan: Plan, name: str, types: TypeRegistry) -> None:
    """Build and compile the target's simulation before the graph goes, so the first messages meet a
    running simulator and compile time is not the publishers' wait."""
    _PREPARED[name] = TargetSimulation(plan, plan.nodes[name].target, types)


class _Input:
    """Where one input port's messages come from: a subscription, or a service's request channel."""

    def __init__(self, node: Node, port: GatewayPort, types: TypeRegistry,
                 components: dict[str, Any] | None = None, times: CoSimulatedTimes | None = None) -> None:
        self.port = port
        self.times = times
        self.codec = types.codec(port.type)
        # what the port's hardware nodes can take, checked before a message goes in (a wider image than a
        # node's line buffers would give wrong pixels with no word); requests are not refused (the asker waits)
        self.checks = [] if port.service else [
            (name, check) for name in port.readers
            if (check := getattr((components or {}).get(name), "check_message", None)) is not None]
        self.refused = 0
        channel = node.graph.plan.channels.get(port.topic) if node.graph.plan is not None else None
        # a reliable topic loses no message without stopping: a refusal there is the launch's end, with the cause
        self.reliable = channel is not None and channel.qos.reliability == "reliable"
        # who asked, in the order their requests went into the hardware (a hardware server answers in order)
        self.asked: deque[tuple[int, str]] = deque()
        self.copied_bytes = 0  # what the CPU copied: each message's body, into the simulator
        self.take: Callable[[], Any]
        if port.service:
            reader = node.graph.open_reader(port.topic, node.name, port.type, node.executor.wake, envelope=True)
            self.take = reader.try_take
        else:
            self.take = node.create_subscription(types.get(port.type), port.topic).try_take

    def next_message(self) -> Any:
        """The next message to go in (LookupError when none waits); a request's asker is remembered."""
        item = self.take()
        if item is None:
            raise LookupError
        if self.port.service:
            request_id, client, item = item
            self.asked.append((request_id, client))
        return item

    def feed(self, top: SimulatedTop) -> None:
        """Take one message and encode it straight into the simulator's input queue (its one copy)."""
        item = self.next_message()
        while not self._fits(item):
            item = self.next_message()
        started = time.thread_time_ns()  # the CPU the copy takes, not the waits of a low-priority thread
        size = self.codec.size(item)
        self.codec.encode(item, top.loan_input(self.port.index, size))
        self.copied_bytes += size
        if self.times is not None:
            self.times.entered(item, top.cycle, time.thread_time_ns() - started)


    def _fits(self, item: Any) -> bool:
        for name, check in self.checks:
            try:
                check(self.port.topic, item)
            except HardwareError as exc:
                if self.reliable:
                    raise HardwareError(f"hardware node {name} on reliable topic {self.port.topic} refused a "
                                        f"message, which a reliable topic may not lose: {exc} (or make "
                                        f"{self.port.topic} best_effort to drop such messages with an error line)"
                                        ) from None
                self.refused += 1
                if self.refused <= 10 or self.refused % 100 == 0:
                    log.error("hardware node %s on %s refused a message (%d so far; it never went in): %s", name,
                              self.port.topic, self.refused, exc)
                return False
        return True


class _Output:
    """Where one output port's messages go: a publisher, or the clients of a service."""

    def __init__(self, node: Node, port: GatewayPort, types: TypeRegistry, asked: deque[tuple[int, str]],
                 times: CoSimulatedTimes | None = None) -> None:
        self.port = port
        self.codec = types.codec(port.type)
        self.asked = asked
        self.times = times
        self.replies = Replies(node, port.service, port.type) if port.service else None
        self.publisher = None if port.service else node.create_publisher(types.get(port.type), port.topic)
        self.copied_bytes = 0  # what the CPU copied: each message's bytes, out of the simulator into the graph

    def ready(self) -> bool:
        """Whether a message can go out now without waiting: a full subscriber holds back this port only (its
        messages stay in the simulator, whose output takes TREADY low), never the whole target."""
        return self.publisher is None or self.publisher.has_room()

    def send(self, body: memoryview, cycle: int = 0) -> None:
        """Publish a message decoded in place from the simulator's memory: its arrays are views there, and
        the transport's send is their one copy (the gateway's process has no other node to keep them).
        ``cycle``: when its last beat left the hardware."""
        started = time.thread_time_ns()
        try:
            message = self.codec.decode(body)
        except SerializationError as exc:
            raise HardwareError(f"{self.port.port.label}: what the hardware sent is not a {self.port.type}: {exc}; "
                                "the node must send one whole message per TLAST") from None
        expected = self.codec.size(message)
        if expected != len(body):
            raise HardwareError(f"{self.port.port.label}: the hardware sent {len(body)} bytes, but a {self.port.type} "
                                f"with the fields it holds is {expected} bytes: the node must send one whole message "
                                "per TLAST (check the lengths it writes and where it ends the message)")
        self.copied_bytes += len(body)
        if self.replies is None:
            assert self.publisher is not None
            self.publisher.publish(message)
            if self.times is not None:
                self.times.left(self.port.topic, message, cycle, time.thread_time_ns() - started)
            return
        if not self.asked:
            raise HardwareError(f"{self.port.port.label}: the hardware answered a request nobody made (a server "
                                "gives one response per request, in order)")
        request_id, client = self.asked.popleft()
        self.replies.send(request_id, client, message)


class CoSimulatedTimes:
    """Each stamped message's time in the hardware, in simulated time: from the cycle it went in (or, when
    the hardware was still sending the previous message of that output, from then on) to the cycle its
    answer on an output left, at the target's clock; and the CPU time the gateway spent copying it in and
    out. A co-simulation runs slower than the hardware would, so messages wait for the simulator in wall
    time; these spans are what ``hetros advise --verify`` puts in their place (``cosimulated_latency``).
    Matched by header stamp (what image filters pass on); unstamped messages are not timed."""

    KEPT = 512

    def __init__(self, clock_mhz: float) -> None:
        self.ns_per_cycle = 1000.0 / clock_mhz
        self._entered: dict[int, tuple[int, int]] = {}  # stamp -> (cycle, CPU ns copying it in)
        self._last_out: dict[str, int] = {}  # output topic -> the cycle its last message left
        self._spans: deque[dict[str, Any]] = deque(maxlen=self.KEPT)
        self._lock = threading.Lock()

    def entered(self, message: Any, cycle: int, cpu_ns: int) -> None:
        stamp = header_stamp(message)
        if stamp is None:
            return
        self._entered[stamp] = (cycle, cpu_ns)
        if len(self._entered) > 4 * self.KEPT:
            del self._entered[next(iter(self._entered))]

    def left(self, topic: str, message: Any, cycle: int, cpu_ns: int) -> None:
        stamp = header_stamp(message)
        went_in = self._entered.get(stamp) if stamp is not None else None
        begin = max(went_in[0], self._last_out.get(topic, 0)) if went_in is not None else 0
        self._last_out[topic] = cycle
        if went_in is None:
            return
        with self._lock:
            self._spans.append({"stamp": stamp, "topic": topic, "sim_ns": round((cycle - begin) * self.ns_per_cycle),
                                "cpu_ns": went_in[1] + cpu_ns})

    def spans(self) -> list[dict[str, Any]]:
        with self._lock:
            return list(self._spans)


class _FramesFromRos1:
    """A ROS 1 subscription whose frames wait, as they came, for the hardware's deframer."""

    def __init__(self, node: Node, peer: Ros1Peer, port: GatewayPort, types: TypeRegistry) -> None:
        self.port = port
        self.frames: deque[bytes] = deque()
        # a connection's thread waits while this many frames wait here: TCP then holds the ROS 1 publisher
        self._room = threading.Semaphore(_QUEUED * 4)
        self._stop = node.graph.stop
        self._wake = node.executor.wake
        self._kind = Ros1Type(types, port.type)
        self.refused = 0
        peer.subscribe(port.topic, self._kind, attach=receive_frames(self._arrived))

    def _arrived(self, frame: bytes) -> None:
        """A frame from a ROS 1 publisher, checked before the RTL sees it: one message of the topic's type,
        exactly (a malformed one made the deframer fail, and with it the whole target)."""
        try:
            self._kind.check_frame(memoryview(frame)[4:])
        except SerializationError as exc:
            self.refused += 1
            if self.refused <= 10 or self.refused % 100 == 0:
                log.error("hardware TCPROS of %s: dropped a malformed frame from ROS 1 (%d so far): %s",
                          self.port.topic, self.refused, exc)
            return
        while not self._room.acquire(timeout=0.2):
            if self._stop.is_set():
                return
        self.frames.append(frame)
        self._wake()

    def feed(self, top: SimulatedTop) -> None:
        try:
            frame = self.frames.popleft()
        except IndexError:
            raise LookupError from None
        self._room.release()
        top.loan_input(self.port.index, len(frame))[:] = frame


class _FramesToRos1:
    """A ROS 1 publication of the frames the hardware's framer makes, sent as they are."""

    def __init__(self, peer: Ros1Peer, port: GatewayPort, types: TypeRegistry, latch: bool) -> None:
        self.port = port
        self.publication = peer.advertise(port.topic, Ros1Type(types, port.type), latch=latch)

    def ready(self) -> bool:
        return True

    def send(self, frame: memoryview) -> None:
        self.publication.publish_frame(frame)


class _ArraysInMemory:
    """What both ways of giving a memory node its messages keep: the port, the read topic's subscription,
    the written topic's publisher, the paths of the type's arrays and its other fields."""

    def __init__(self, node: Node, read: GatewayPort, write: GatewayPort, types: TypeRegistry) -> None:
        from ...msg import array_fields

        cls = types.get(read.type)
        self.port = read
        self.take: Callable[[], Any] = node.create_subscription(cls, read.topic).try_take
        self.publisher = node.create_publisher(cls, write.topic)
        self.arrays = [f.path for f in array_fields(types, read.type) if f.length is None]
        tops = {path[0] for path in self.arrays}
        self.plain = [name for name in cls.__fieldnames__ if name not in tops]

    def loan_answer(self, message: Any, elements: list[int]) -> Any:
        """A loaned answer to ``message``: its arrays ``elements`` long, its other fields copied."""
        from ...msg import copy

        answer = self.publisher.loan(**{"__".join(path): n for path, n in zip(self.arrays, elements, strict=True)})
        for name in self.plain:
            value = getattr(message, name)
            setattr(answer, name, copy(value) if hasattr(value, "__msgtype__") else value)
        return answer


class _InMemory(_ArraysInMemory):
    """A hardware node that reads one topic's messages and writes another's in memory (``hw.designs._memory``): each
    message in goes as a descriptor of its arrays and of a loaned answer's; the node's completion publishes
    the answer. The arrays are the shared-memory slots themselves: the CPU copies none of their bytes."""

    def __init__(self, node: Node, read: GatewayPort, write: GatewayPort, types: TypeRegistry,
                 top: SimulatedTop) -> None:
        if not isinstance(top, VerilatedTop):
            raise HardwareError(f"{read.topic}: a hardware node reading messages in memory runs in Verilator only")
        super().__init__(node, read, write, types)
        self.top = top
        self.pending: deque[tuple[Any, Any, list[int], int]] = deque()
        self.copied_bytes = 0  # array bytes the CPU copied (a loan too small for a slot is copied once)
        self.messages = 0
        self.cycles = 0  # from each descriptor going in to its completion coming out
        self._started: deque[int] = deque()

    def feed(self, top: SimulatedTop) -> None:
        from ...msg import get_path

        message = self.take()
        if message is None:
            raise LookupError
        arrays = [np.asarray(get_path(message, path)) for path in self.arrays]
        answer = self.loan_answer(message, [len(a) for a in arrays])
        written = [np.asarray(get_path(answer, path)) for path in self.arrays]
        windows, words = [], []
        for array, writable in [(a, False) for a in arrays] + [(a, True) for a in written]:
            # the hardware gets the physical address the simulated board placed the slot's array at
            physical = self.top.allow(array.ctypes.data, array.nbytes, writable)
            windows.append(physical)
            words += [physical, array.nbytes]
        descriptor = np.array(words, "<u8").tobytes()
        top.loan_input(self.port.index, len(descriptor))[:] = descriptor
        self.pending.append((message, answer, windows, sum(a.nbytes for a in written)))
        self._started.append(top.cycle)

    def complete(self, _body: memoryview) -> None:
        if not self.pending:
            raise HardwareError(f"{self.port.port.label}: the hardware completed a message nobody gave it")
        message, answer, windows, nbytes = self.pending.popleft()
        self.cycles += self.top.cycle - self._started.popleft()
        for physical in windows:
            self.top.forbid(physical)
        if not self.publisher.sends_in_place(answer):
            self.copied_bytes += nbytes  # a loan below the slot threshold: its arrays are copied into the slot
        self.publisher.publish(answer)
        self.messages += 1
        del message


class _BoardMemory(_ArraysInMemory):
    """A hardware node that reads one topic's messages and writes another's in memory, on a board: each
    message's arrays are copied into buffers PYNQ's ``allocate`` placed in contiguous memory (CMA), the node
    gets their physical addresses in a descriptor (``hw.designs._memory``), and its completion copies the answer's
    arrays out into a loaned message. One message at a time: the buffers are reused. In co-simulation the
    same code runs against the simulated overlay, whose buffers sit in a simulated physical address space."""

    def __init__(self, node: Node, read: GatewayPort, write: GatewayPort, types: TypeRegistry,
                 overlay: Any) -> None:
        super().__init__(node, read, write, types)
        self.overlay = overlay
        self.buffers: list[tuple[Any, Any]] = []  # (in, out) per array, grown as messages need
        self.pending: deque[tuple[Any, list[int]]] = deque()
        self.copied_bytes = 0
        self.messages = 0

    def _buffer(self, index: int, size: int) -> tuple[Any, Any]:
        from .board import allocate, release

        while len(self.buffers) <= index:
            self.buffers.append((allocate(8, overlay=self.overlay), allocate(8, overlay=self.overlay)))
        given, answer = self.buffers[index]
        if len(given) < size:
            for old in (given, answer):
                release(old, self.overlay)
            given, answer = allocate(size, overlay=self.overlay), allocate(size, overlay=self.overlay)
            self.buffers[index] = (given, answer)
        return given, answer

    def next_message(self) -> bytes:
        """The descriptor of the next message's arrays and of the answer's (LookupError when none waits, or
        while the hardware still works on the last one)."""
        from ...msg import get_path

        if self.pending:
            raise LookupError
        message = self.take()
        if message is None:
            raise LookupError
        arrays = [np.ascontiguousarray(get_path(message, path)).view(np.uint8).reshape(-1) for path in self.arrays]
        words: list[int] = []
        answers = []
        for index, array in enumerate(arrays):
            given, answer = self._buffer(index, max(8, array.nbytes))
            given[:array.nbytes] = array
            given.flush()
            words += [given.physical_address, array.nbytes]
            answers.append(answer)
            self.copied_bytes += array.nbytes
        for array, answer in zip(arrays, answers, strict=True):
            words += [answer.physical_address, array.nbytes]
        self.pending.append((message, [a.nbytes for a in arrays]))
        return np.array(words, "<u8").tobytes()

    def ready(self) -> bool:
        return self.publisher.has_room()

    def send(self, _completion: memoryview) -> None:
        """The node's completion: the answer's arrays copied out of their buffers into a loaned message."""
        from ...msg import get_path

        if not self.pending:
            raise HardwareError(f"{self.port.port.label}: the hardware completed a message nobody gave it")
        message, sizes = self.pending.popleft()
        answer = self.loan_answer(message, [len(np.asarray(get_path(message, path))) for path in self.arrays])
        for index, (path, size) in enumerate(zip(self.arrays, sizes, strict=True)):
            out = self.buffers[index][1]
            out.invalidate()
            target = np.asarray(get_path(answer, path)).view(np.uint8).reshape(-1)
            target[:] = out[:size]
            self.copied_bytes += size
        self.publisher.publish(answer)
        self.messages += 1


class _Completions:
    """The output side of an :class:`_InMemory`: each beat out of the port is a finished answer."""

    def __init__(self, port: GatewayPort, pair: _InMemory) -> None:
        self.port, self.pair = port, pair

    def ready(self) -> bool:
        return self.pair.publisher.has_room()

    def send(self, body: memoryview) -> None:
        self.pair.complete(body)


class _StuckInputs:
    """Stops the launch when a hardware node holds a waiting message at its input without taking a beat for
    ``limit`` cycles (the target's ``stuck_cycles``; 0.1 s at 100 MHz by default: a node streams its input).
    Before, its publishers stopped a minute later with a timeout that blamed the gateway's process."""

    def __init__(self, top: SimulatedTop, ports: list[GatewayPort], limit: int, target: str) -> None:
        self.top, self.ports = top, [p for p in ports if not p.memory_node]
        self.limit, self.target = limit, target
        self.beats = [-1] * len(self.ports)
        # per input, the cycle its last beat moved (or it had nothing waiting), and the target's cycles held back by
        # software then: a node that waits because a software subscriber is full is not stuck
        self.since = [(0, 0)] * len(self.ports)

    def _stalled(self, slot: int) -> int:
        cycle, waited = self.since[slot]
        return (self.top.cycle - cycle) - (self.top.waited() - waited)

    def cycles_left(self, most: int) -> int:
        """Cycles the next run may take (up to ``most``) before a waiting input reaches the bound: a slow run
        (a traced one) must not let publishers time out before the node is named."""
        waiting = [self.limit + 1 - self._stalled(slot) for slot, port in enumerate(self.ports)
                   if self.top.queued(port.index)]
        return max(1, min([most, *waiting]))

    def look(self) -> None:
        top = self.top
        for slot, port in enumerate(self.ports):
            beats = top.stats(False, port.index)[1]
            if beats != self.beats[slot] or not top.queued(port.index):
                self.beats[slot], self.since[slot] = beats, (top.cycle, top.waited())
            elif (stalled := self._stalled(slot)) > self.limit:
                nodes = ", ".join(port.readers) or "the hardware"
                note = top.finish_trace()
                raise HardwareError(
                    f"{port.port.label}: hardware node {nodes} has taken no beat for {stalled} "
                    f"cycles while a message waits (TREADY low at its input, cycle {top.cycle - 1}): check its TREADY "
                    f"logic, or raise targets.{self.target}.stuck_cycles ({self.limit}) for a node that may "
                    f"rightly wait that long{'; ' + note if note else ''}")


def _ros1_peer(node: Node, plan: Plan, target: str) -> Ros1Peer | None:
    spec = plan.targets[target]
    if not spec.ros1_export and not spec.ros1_import:
        return None
    peer = Ros1Peer(f"/{plan.name}_{target}", plan.ros1_master, plan.ros1_host, node.graph.stop)
    log.info("fpga target %s is the ROS 1 node %s (hardware TCPROS: publishes %s, subscribes %s)", target,
             peer.name, ", ".join(spec.ros1_export) or "nothing", ", ".join(spec.ros1_import) or "nothing")
    return peer


def gateway(node: Node) -> None:
    """Run the fpga target's hardware in Verilator, its gateway ports fed from and drained to the graph."""
    plan = node.graph.plan
    if plan is None:
        raise HardwareError("a gateway runs inside a launch: it needs the plan of the project")
    target = str(node.get_parameter("target"))
    types = node.graph.types
    simulation = _PREPARED.pop(node.name, None) or TargetSimulation(plan, target, types)
    if plan.targets[target].board:
        _run_board(node, plan, target, simulation, types)
        return
    top = simulation.top
    nice = os.environ.get(SIMULATOR_NICE_VARIABLE, "")
    if nice:
        try:
            os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), int(nice))
        except (ValueError, OSError) as exc:
            raise HardwareError(f"{SIMULATOR_NICE_VARIABLE} must be a nice value this user may set (0..19), not "
                                f"{nice!r}: {exc}") from None
    log.info("fpga target %s in %s (%d gateway ports; built in %.1f s)", target, simulation.simulator,
             len(top.inputs) + len(top.outputs), simulation.compile_seconds)
    # Amaranth's simulator runs thousands of cycles a second, not millions: it idles after fewer
    idle_cycles = _IDLE_CYCLES if simulation.simulator == "verilator" else _QUIET_AFTER_TRAFFIC
    peer = _ros1_peer(node, plan, target)
    answers = {o.memory_node: o for o in simulation.outputs if o.memory_node}
    times = CoSimulatedTimes(simulation.clock_mhz)
    in_memory = {p.memory_node: _InMemory(node, p, answers[p.memory_node], types, top)
                 for p in simulation.inputs if p.memory_node}
    inputs: list[_Input | _FramesFromRos1 | _InMemory] = [
        in_memory[port.memory_node] if port.memory_node else
        _FramesFromRos1(node, peer, port, types) if peer is not None and port.ros1
        else _Input(node, port, types, simulation.components, times) for port in simulation.inputs]
    asked = {i.port.service: i.asked for i in inputs if isinstance(i, _Input) and i.port.service}
    latched = {t for t, q in plan.ros1_qos.items() if q.keeps_history} | {
        c.name for c in plan.channels.values() if c.qos.keeps_history}
    outputs: list[_Output | _FramesToRos1 | _Completions] = [
        _Completions(port, in_memory[port.memory_node]) if port.memory_node else
        _FramesToRos1(peer, port, types, port.topic in latched) if peer is not None and port.ros1
        else _Output(node, port, types, asked.get(port.service, deque()), times) for port in simulation.outputs]
    node.figures = lambda: {**_figures(simulation, in_memory), "spans": times.spans()}
    stop = node.graph.stop
    wall = 0.0
    pushed = popped = last_moved = 0
    quiet = idle_cycles
    stuck = _StuckInputs(top, simulation.inputs, plan.targets[target].stuck_cycles, target)
    try:
        while not stop.is_set():
            seen = node.executor.generation
            for each in inputs:
                try:
                    while top.queued(each.port.index) < _QUEUED:
                        each.feed(top)
                        pushed += 1
                        last_moved = top.cycle
                except LookupError:
                    pass  # nothing more to take now
            working = pushed > popped and top.cycle - last_moved < _IN_FLIGHT_CYCLES
            started = time.perf_counter()
            events = top.run(stuck.cycles_left(_CHUNK), _CHUNK if working else quiet)
            wall += time.perf_counter() - started
            stuck.look()
            held = False  # an output whose subscriber is full: its messages wait in the simulator
            for out in outputs:
                while (produced := top.front(out.port.index)) is not None:
                    if not out.ready():
                        del produced
                        held = True
                        break
                    try:
                        if isinstance(out, _Output):
                            out.send(produced, top.cycle)
                        else:
                            out.send(produced)
                    finally:
                        del produced
                        top.drop(out.port.index)
                    popped += 1
                    last_moved = top.cycle
            waiting = any(top.queued(i.port.index) for i in inputs)
            if events & IDLE and not waiting:
                # a subscriber that takes does not wake this node: with an output held, look again soon
                node.executor.wait(seen, _HELD_POLL if held else 0.1)
                quiet = _QUIET_AFTER_TRAFFIC if node.executor.generation != seen else idle_cycles
            elif held and events & IDLE:
                time.sleep(_HELD_POLL)  # inputs wait on a held output: nothing moves until its subscriber takes
    finally:
        if peer is not None:
            peer.close()
        _report(simulation, wall)
        for name, pair in in_memory.items():
            index = [m.prefix for m in simulation.memories].index(f"m_axi_{name}")
            reads, writes = top.memory_stats(index) if isinstance(top, VerilatedTop) else (0, 0)
            log.info("  hardware node %s in memory: %d messages, %.0f cycles per message, %d beats read and %d "
                     "written over AXI4, %.0f array bytes copied by the CPU per message", name, pair.messages,
                     pair.cycles / max(1, pair.messages), reads, writes, pair.copied_bytes / max(1, pair.messages))
        for end in (*inputs, *outputs):
            if isinstance(end, _Input | _Output) and end.copied_bytes:
                moved = simulation.top.stats(isinstance(end, _Output), end.port.index)[0]
                log.info("  %s: %.0f bytes copied by the CPU per message", end.port.port.label,
                         end.copied_bytes / max(1, moved))
        for port in simulation.outputs:
            partial = top.partial(port.index)
            if partial:
                log.error("%s: %d bytes arrived without TLAST ending their message", port.port.label, partial)
        if note := top.finish_trace():
            log.info("fpga target %s: %s", target, note)
        simulation.close()


gateway.prepare = _prepare  # type: ignore[attr-defined]


def _figures(simulation: TargetSimulation, in_memory: dict[str, _InMemory] | None = None) -> dict[str, Any]:
    """What ``hetros top`` shows of a gateway: cycles simulated, and per port messages and cycles per message."""
    top = simulation.top
    ports = {}
    for output, each in ((False, simulation.inputs), (True, simulation.outputs)):
        for port in each:
            messages, beats, busy = top.stats(output, port.index)
            ports[port.port.label] = {"messages": messages, "beats": beats,
                                      "cycles_per_message": busy / messages if messages else 0.0,
                                      "waited_per_message": top.waited(output, port.index) / messages
                                      if messages else 0.0}
    memory = {name: {"messages": pair.messages, "copied_bytes_per_message": pair.copied_bytes / max(1, pair.messages)}
              for name, pair in (in_memory or {}).items()}
    return {"cycles": top.cycle, "waited": top.waited(), "clock_mhz": simulation.clock_mhz, "ports": ports,
            "memory": memory}


def _report(simulation: TargetSimulation, wall: float) -> None:
    """Simulated time beside wall time: per gateway port, cycles per message and µs at the target clock."""
    top = simulation.top
    cycles = top.cycle
    rate = cycles / wall if wall > 0 else 0.0
    waited = top.waited()
    log.info("fpga target %s: %d cycles simulated (%.3f ms at %g MHz, %s) in %.3f s of simulation (%.2f M cycles/s)%s",
             simulation.target, cycles, cycles / simulation.clock_mhz / 1000, simulation.clock_mhz,
             simulation.clock.source, wall, rate / 1e6,
             f"; {waited} of them with an output held back by a full software subscriber" if waited else "")
    for output, ports in ((False, simulation.inputs), (True, simulation.outputs)):
        for port in ports:
            messages, beats, busy = top.stats(output, port.index)
            if messages:
                per = busy / messages
                held = top.waited(output, port.index)
                log.info("  %s: %d messages, %d beats, %.0f cycles per message (%.2f µs at %g MHz)%s", port.port.label,
                         messages, beats, per, per / simulation.clock_mhz, simulation.clock_mhz,
                         f"; besides, {held / messages:.0f} cycles per message waiting on software" if held else "")


# what a board's receive channel can take in one message, unless the port's messages are known to be smaller
_RECEIVE_BYTES = 1 << 22


def _run_board(node: Node, plan: Plan, target: str, simulation: TargetSimulation, types: TypeRegistry) -> None:
    """The gateway as a board runs it: PYNQ's surface (``board.py`` beside this module), one AXI DMA per
    gateway port, each message a DMA transfer between a buffer the DMA reaches and the hardware's stream."""
    from ...hw import export, top_name
    from ..launcher._registry import session_folder
    from .board import allocate, open_overlay, read_manifest

    board = plan.targets[target].board
    if any(p.ros1 for p in (*simulation.inputs, *simulation.outputs)):
        raise HardwareError(f"fpga target {target}: hardware TCPROS runs under co-simulation only; remove board: "
                            "or leave its ROS 1 topics to the bridge")
    exported = Path(plan.root) / "hw" / target / f"{top_name(target)}.board.json"  # `hetros hw export -o hw/<t>`
    manifest = exported
    if not exported.exists():
        folder = session_folder(node.graph.session) / "board" / target
        export(plan, target, board, folder, types)
        manifest = folder / exported.name
    overlay = open_overlay(manifest, simulation)
    ports = {p.port.prefix: p for p in (*simulation.inputs, *simulation.outputs)}
    answers = {o.memory_node: o for o in simulation.outputs if o.memory_node}
    in_memory = {p.port.prefix: _BoardMemory(node, p, answers[p.memory_node], types, overlay)
                 for p in simulation.inputs if p.memory_node}
    completing = {answers[m.port.memory_node].port.prefix: m for m in in_memory.values()}
    inputs: dict[str, _Input | _BoardMemory] = {
        p.port.prefix: in_memory.get(p.port.prefix) or _Input(node, p, types) for p in simulation.inputs}
    asked = {i.port.service: i.asked for i in inputs.values() if isinstance(i, _Input) and i.port.service}
    sends: list[tuple[Any, _Input | _BoardMemory, list[Any]]] = []
    receives: list[tuple[Any, _Output | _BoardMemory, Any]] = []
    for entry in read_manifest(manifest)["dmas"]:
        dma = getattr(overlay, entry["name"])
        if entry["channel"] == "sendchannel":
            sends.append((dma.sendchannel, inputs[entry["interface"]], [allocate(4096)]))
        else:
            port = ports[entry["interface"]]
            out = completing.get(entry["interface"]) or _Output(node, port, types, asked.get(port.service, deque()))
            buffer = allocate(_RECEIVE_BYTES)
            dma.recvchannel.transfer(buffer)
            receives.append((dma.recvchannel, out, buffer))
    log.info("fpga target %s on board %s through %s (%d DMA channels)", target, board, type(overlay).__name__,
             len(sends) + len(receives))
    stop = node.graph.stop
    in_flight = 0
    try:
        while not stop.is_set():
            seen = node.executor.generation
            moved = False
            for channel, source, held in sends:
                if not channel.idle:
                    continue
                try:
                    message = source.next_message()
                except LookupError:
                    continue
                if isinstance(source, _BoardMemory):  # a descriptor of buffers the node reads and writes
                    size = len(message)
                    held[0][:size] = np.frombuffer(message, np.uint8)
                    held[0].flush()
                    channel.transfer(held[0], 0, size)
                    in_flight += 1
                    moved = True
                    continue
                size = source.codec.size(message)
                if size > len(held[0]):
                    held[0] = allocate(max(size, 2 * len(held[0])))
                source.codec.encode(message, memoryview(held[0])[:size])
                held[0].flush()
                channel.transfer(held[0], 0, size)
                in_flight += 1
                moved = True
            for channel, sink, buffer in receives:
                if channel.idle:
                    buffer.invalidate()
                    sink.send(memoryview(buffer)[:channel.transferred])
                    channel.transfer(buffer)
                    in_flight = max(0, in_flight - 1)
                    moved = True
            if not moved:
                node.executor.wait(seen, 0.001 if in_flight else 0.05)
    finally:
        log.info("fpga target %s on board %s: %d cycles run", target, board, simulation.top.cycle)
        simulation.close()
