"""One process' share of the graph: the transports its nodes' endpoints use.

For each endpoint the plan says which peers live in this process (served by
the inproc transport, the object itself), which live in other processes on
this host (served by shm) and which on other hosts (dds). A writer feeds all
of them; a reader drains all of them.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .._errors import TransportError, UndeclaredEndpointError
from .._log import get_logger
from ..msg import (
    LoanBuffer,
    Message,
    TypeRegistry,
    array_fields,
    default_maker,
    freeze,
    hand_over,
    loaned_array,
    registry,
    set_path,
)
from ..msg import copy as copy_message
from ..plan import LAUNCHER, SERVICE_QOS, ChannelPlan, EdgePlan, Plan, request_channel, service_of
from ..transport import (
    DEFAULT_QOS,
    Codec,
    EnvelopeCodec,
    InprocTopic,
    MessageCodec,
    QoS,
    Reader,
    ShmDomain,
    Wake,
    Writer,
    carried_message,
)
from ..transport.dds import HOST_LEASE, DdsDomain, DdsEdgeReader, DdsEdgeWriter, edge_topic
from ..transport.tcpros import (
    Ros1Peer,
    Ros1ServiceCaller,
    Ros1ServiceServer,
    Ros1ServiceType,
    Ros1Type,
    Ros1Writer,
    SocketWaiter,
    open_ros1_reader,
)
from ._executor import WaitSource

log = get_logger("hetros.graph")


def _hand_over(item: Any, copy_arrays: bool) -> Any:
    """Freeze a message (or a service envelope's message) on its way out; see ``msg.hand_over``."""
    message = carried_message(item)
    if message is not None:
        hand_over(message, copy_arrays)
    return item


class _FanoutWriter(Writer):
    """Feeds the in-process FIFOs and the shared-memory service of one endpoint."""

    def __init__(self, parts: list[Writer], types: TypeRegistry) -> None:
        self._parts = parts
        self._types = types
        self._lender = next((p for p in parts if p.lends_slots), None)
        self._local = any(p is not self._lender for p in parts)
        if len(parts) == 1:
            # the common case, one transport: a loan needs no copy for other parts
            self.write = self._write_one  # type: ignore[method-assign]
            self._write_part = parts[0].write

    def loan_maker(self, cls: type[Message], sizes: dict[str, int]) -> Callable[[], Message]:
        """What makes loans of these array lengths (``Publisher.loan`` keeps it): messages to
        fill in place, their arrays in a shared-memory slot when a process reads them and
        they are large, otherwise in memory hetros owns (sent inline)."""
        sizes = {name.replace("__", "."): length for name, length in sizes.items()}
        lender = self._lender
        slot_maker = None if lender is None else lender.slot_loan_maker(sizes)
        if slot_maker is not None:
            return slot_maker
        arrays = self._arrays_of(cls, sizes)
        blank = default_maker(cls)
        if len(arrays) == 1 and len(arrays[0][0]) == 1:  # one top-level array, the common loan
            (name,), dtype, length = arrays[0]
            shape, nbytes = (length,), length * dtype.itemsize

            def one_array() -> Message:  # loaned_array inlined: a third of a small loan's cost
                message: Message = blank()
                setattr(message, name, np.ndarray(shape, dtype, LoanBuffer(nbytes)))
                return message
            return one_array

        def each_array() -> Message:
            message: Message = blank()
            for path, dtype, length in arrays:
                set_path(message, path, loaned_array(length, dtype))
            return message
        return each_array

    def _arrays_of(self, cls: type[Message], sizes: dict[str, int]) -> list[tuple[tuple[str, ...], Any, int]]:
        wanted = dict(sizes)
        arrays = []
        for field in array_fields(self._types, cls.__msgtype__):
            length = wanted.pop(".".join(field.path), None)
            if length is not None and field.length is None:
                arrays.append((field.path, field.dtype, length))
        if wanted:
            raise TransportError(f"{cls.__msgtype__} has no variable-length primitive array "
                                 f"{', '.join(wanted)}")
        return arrays

    def _write_one(self, message: Any) -> None:
        if isinstance(message, Message):  # a topic's message: sealed here without looking for an envelope
            hand_over(message, self._local)
        else:
            _hand_over(message, self._local)
        self._write_part(message)

    def write(self, message: Any) -> None:
        lender = self._lender
        if lender is not None and lender.owns_loan(message):
            others = [part for part in self._parts if part is not lender]
            if others:
                # the slot leaves with the shared-memory send: in-process readers get their own copy
                local = freeze(copy_message(message))
                for part in others:
                    part.write(local)
            lender.write(_hand_over(message, copy_arrays=False))
            return
        _hand_over(message, copy_arrays=self._local)
        for part in self._parts:
            part.write(message)

    def assert_liveliness(self) -> None:
        for part in self._parts:
            part.assert_liveliness()

    def close(self) -> None:
        for part in self._parts:
            part.close()


class _MergedReader(Reader):
    def __init__(self, parts: list[Reader]) -> None:
        self._parts = parts

    def try_take(self) -> Any | None:
        for part in self._parts:
            item = part.try_take()
            if item is not None:
                return item
        return None

    def pending(self) -> bool:
        return any(part.pending() for part in self._parts)

    def liveliness(self) -> tuple[int, int] | None:
        counts = [c for c in (part.liveliness() for part in self._parts) if c is not None]
        return (sum(c[0] for c in counts), sum(c[1] for c in counts)) if counts else None

    def close(self) -> None:
        for part in self._parts:
            part.close()


class _Relay:
    """A wake-up target fixed later: readers opened at start-up, before their node runs."""

    def __init__(self) -> None:
        self.target: Wake | None = None

    def __call__(self) -> None:
        target = self.target
        if target is not None:
            target()


class _Retained(Reader):
    """A reader opened from the plan at start-up; it outlives the node that uses it.

    When its node fails and restarts, the FIFO (and its place in the publisher's credits)
    stays, so the restarted node resumes where the failed one stopped.
    """

    def __init__(self, inner: Reader, relay: _Relay, release: Callable[[_Retained], None]) -> None:
        self.inner = inner
        self.relay = relay
        self._release = release
        self.try_take = inner.try_take  # type: ignore[method-assign]  # one call less per message
        self.pending = inner.pending  # type: ignore[method-assign]

    def try_take(self) -> Any | None:
        return self.inner.try_take()

    def pending(self) -> bool:
        return self.inner.pending()

    def liveliness(self) -> tuple[int, int] | None:
        return self.inner.liveliness()

    def close(self) -> None:
        self.relay.target = None
        self._release(self)


class Graph:
    """Endpoints of the nodes hosted by this process, wired as the plan says."""

    def __init__(
        self,
        plan: Plan | None,
        process: str = LAUNCHER,
        session: str = "",
        stop: threading.Event | None = None,
        types: TypeRegistry | None = None,
    ) -> None:
        self.plan = plan
        self.process = process
        self.session = session
        self.stop = stop or threading.Event()
        # why the graph stopped, when the launcher said ("target sorter died (...)"): interrupted
        # waits name it
        self.stop_reason = ""
        self.types = types or registry()
        self._lock = threading.Lock()
        self._inproc: dict[str, InprocTopic] = {}
        self._adhoc_qos: dict[str, QoS] = {}
        self._shm: ShmDomain | None = None
        self._codecs: dict[tuple[str, bool], Codec] = {}
        self._stop_hooks: list[Callable[[], None]] = []
        self._prepared: dict[tuple[str, str], _Retained] = {}
        self._ros1: _Ros1Nodes | None = None
        self._dds: DdsDomain | None = None
        self._dds_writers: dict[str, DdsEdgeWriter] = {}
        self._dds_readers: list[tuple[str, DdsEdgeReader]] = []
        # the plan's edges, by (channel, publisher) and (channel, subscriber): the runtime wires
        # what they say and never works the transport out again
        self._out: dict[tuple[str, str], list[EdgePlan]] = {}
        self._in: dict[tuple[str, str], list[EdgePlan]] = {}
        for edge in plan.edges if plan is not None else ():
            self._out.setdefault((edge.channel, edge.publisher), []).append(edge)
            self._in.setdefault((edge.channel, edge.subscriber), []).append(edge)

    def prepare(self, nodes: list[str]) -> None:
        """Open every declared subscription of ``nodes`` now (static initialisation).

        Messages published before a node's code reaches ``create_subscription``
        wait in its FIFO instead of being lost to start-up order.
        """
        assert self.plan is not None
        for channel in self.plan.channels.values():
            for node in channel.subscribers:
                if node in nodes:
                    relay = _Relay()
                    reader = self._open_reader(channel, node, channel.type, relay, None,
                                               envelope=channel.kind != "topic")
                    self._prepared[(channel.name, node)] = _Retained(reader, relay, self._give_back(channel.name, node))
        # writers to other hosts exist before the nodes run, so remote readers match them meanwhile
        for edge in self.plan.edges:
            if edge.transport == "dds" and edge.publisher in nodes:
                channel = self.plan.channels[edge.channel]
                self._dds_writer(channel.name, channel.type, channel.kind != "topic", channel.qos)
        for node in nodes:
            spec = self.plan.nodes[node]
            if self.plan.speaks_ros1(node):
                wanted = [(topic, False) for topic in spec.subscribe]
                wanted += [(request_channel(service), True) for service in spec.services]
                for name, envelope in wanted:
                    relay = _Relay()
                    reader = self._ros1_nodes().open_reader(name, node, relay, envelope=envelope)
                    self._prepared[(name, node)] = _Retained(reader, relay, self._give_back(name, node))

    def _give_back(self, channel: str, node: str) -> Callable[[_Retained], None]:
        def release(reader: _Retained) -> None:
            with self._lock:
                if not self.stop.is_set():
                    self._prepared[(channel, node)] = reader
                    return
            reader.inner.close()
        return release

    def forget(self, node: str) -> None:
        """``node`` finished and will not run again: close the readers kept for its restart, so
        that its subscriber slots are left (publishers neither wait for room nor linger there)."""
        self._close_prepared(node)

    def _close_prepared(self, node: str | None) -> None:
        """Close the readers kept from start-up for ``node`` (every node's with None)."""
        with self._lock:
            keys = [key for key in self._prepared if node is None or key[1] == node]
            readers = [self._prepared.pop(key) for key in keys]
        for reader in readers:
            reader.inner.close()

    def wake_source(self, node: str) -> WaitSource | None:
        """What ``node``'s executor blocks on besides its condition: a ROS 1 node's TCPROS
        connections, or the shm wake channel if any of its readers is fed from another process."""
        if self.plan is None:
            return None
        if self._speaks_ros1(node):
            return self._ros1_nodes().waiter(node)
        if any(edge.transport == "shm" and edge.subscriber == node for edge in self.plan.edges):
            return self._domain().wake_channel(node)
        return None

    def on_stop(self, hook: Callable[[], None]) -> None:
        """Call ``hook`` when the graph stops (executors and blocked takes wake up)."""
        with self._lock:
            self._stop_hooks.append(hook)
        if self.stop.is_set():
            hook()

    def shutdown(self) -> None:
        """Stop every node of this process: set the stop flag and wake everything waiting."""
        self.stop.set()
        with self._lock:
            hooks = list(self._stop_hooks)
        for hook in hooks:
            hook()

    @classmethod
    def standalone(cls) -> Graph:
        """A graph with no project: every endpoint allowed, everything in-process."""
        return cls(None)

    # -- declarations ----------------------------------------------------------------------

    def channel(self, name: str, node: str, role: str) -> ChannelPlan | None:
        if self.plan is None:
            return None
        channel = self.plan.channels.get(name)
        members = () if channel is None else (channel.publishers if role == "publish" else channel.subscribers)
        if channel is None or node not in members:
            yaml_key = {"publish": "publish", "subscribe": "subscribe"}.get(role, role)
            raise UndeclaredEndpointError(
                f"node {node!r} creates a {role} endpoint on {name!r} that the project file does "
                f"not declare: add it under nodes.{node}.{yaml_key} (static plan: no endpoint "
                "appears at run time that the plan has not wired)"
            )
        return channel

    def qos_of(self, name: str, requested: QoS | None) -> QoS:
        if self.plan is not None and name in self.plan.channels:
            declared = self.plan.channels[name].qos
            if requested is not None and requested != declared:
                log.warning("%s: the code asks for %s but the project file's QoS applies: %s "
                            "(change it under topics.%s)", name, requested, declared, name)
            return declared
        with self._lock:
            return self._adhoc_qos.setdefault(name, requested or DEFAULT_QOS)

    # -- transports ------------------------------------------------------------------------

    def _inproc_topic(self, name: str, qos: QoS) -> InprocTopic:
        with self._lock:
            topic = self._inproc.get(name)
            if topic is None:
                topic = InprocTopic(name, qos, self.stop)
                self._inproc[name] = topic
            return topic

    def _domain(self) -> ShmDomain:
        with self._lock:
            if self._shm is None:
                self._shm = ShmDomain(self.session, self.process)
            return self._shm

    def _codec(self, typename: str, envelope: bool) -> Codec:
        key = (typename, envelope)
        codec = self._codecs.get(key)
        if codec is None:
            inner = MessageCodec(self.types, typename)
            codec = EnvelopeCodec(inner) if envelope else inner
            self._codecs[key] = codec
        return codec

    def _dds_domain(self) -> DdsDomain:
        with self._lock:
            if self._dds is None:
                assert self.plan is not None and self.plan.local_host
                hosts = self.plan.hosts
                self._dds = DdsDomain(self.plan.dds_domain, interface=hosts[self.plan.local_host].address,
                                      peers=[h.address for h in hosts.values()], lease=HOST_LEASE)
            return self._dds

    def _dds_writer(self, name: str, typename: str, envelope: bool, qos: QoS) -> DdsEdgeWriter:
        """One DDS writer per channel and process (every node of the process writes through it)."""
        writer = self._dds_writers.get(name)
        if writer is None:
            assert self.plan is not None
            writer = DdsEdgeWriter(self._dds_domain(), edge_topic(self.plan.name, self.plan.local_host, name),
                                   self._codec(typename, envelope), qos)
            with self._lock:
                writer = self._dds_writers.setdefault(name, writer)
        return writer

    def wait_for_remote_readers(self, timeout: float = 10.0) -> list[str]:
        """Wait until each writer to other hosts is matched by every remote reader the plan has for it,
        so nothing reliable is published before its remote subscribers hear it; return the channels
        still short when ``timeout`` passed (they are logged)."""
        if not self._dds_writers:
            return []
        assert self.plan is not None
        expected = {name: len({e.subscriber for e in self.plan.edges if e.channel == name and e.transport == "dds"
                               and self.plan.host_of(e.publisher) == self.plan.local_host})
                    for name in self._dds_writers}
        deadline = time.monotonic() + timeout
        while not self.stop.is_set():
            short = [n for n, w in self._dds_writers.items() if w.matched() < expected[n]]
            if not short or time.monotonic() > deadline:
                for name in short:
                    log.warning("%s: %d of %d remote subscribers matched after %g s; publishing anyway",
                                name, self._dds_writers[name].matched(), expected[name], timeout)
                return short
            time.sleep(0.01)
        return []

    def _ros1_nodes(self) -> _Ros1Nodes:
        with self._lock:
            if self._ros1 is None:
                assert self.plan is not None
                self._ros1 = _Ros1Nodes(self.plan, self.types, self.stop)
            return self._ros1

    def _speaks_ros1(self, node: str) -> bool:
        return self.plan is not None and node in self.plan.nodes and self.plan.speaks_ros1(node)

    def open_writer(self, name: str, node: str, typename: str, *, qos: QoS | None = None,
                    envelope: bool = False) -> Writer:
        if self._speaks_ros1(node):
            return self._ros1_nodes().open_writer(name, node, envelope=envelope)
        channel = self.channel(name, node, "publish")
        effective = self.qos_of(name, qos)
        if channel is None:
            return _FanoutWriter([self._inproc_topic(name, effective).open_writer()], self.types)
        transports = {edge.transport for edge in self._out.get((name, node), ())}
        parts: list[Writer] = []
        if "inproc" in transports:
            parts.append(self._inproc_topic(name, effective).open_writer())
        if "shm" in transports:
            parts.append(self._domain().open_writer(name, self.process, effective,
                                                    self._codec(typename, envelope)))
        if "dds" in transports:
            parts.append(self._dds_writer(name, typename, envelope, effective))
        return _FanoutWriter(parts, self.types)

    def open_reader(self, name: str, node: str, typename: str, wake: Wake, *,
                    qos: QoS | None = None, envelope: bool = False) -> Reader:
        ros1 = self._speaks_ros1(node)
        channel = None
        if not ros1:
            channel = self.channel(name, node, "subscribe")
            if channel is None:
                return self._inproc_topic(name, self.qos_of(name, qos)).open_reader(node, wake)
        with self._lock:
            prepared = self._prepared.pop((name, node), None)
        if prepared is not None:
            prepared.relay.target = wake
            wake()
            return prepared
        if channel is None:
            return self._ros1_nodes().open_reader(name, node, wake, envelope=envelope)
        return self._open_reader(channel, node, typename, wake, qos, envelope=envelope)

    def _open_reader(self, channel: ChannelPlan, node: str, typename: str, wake: Wake,
                     qos: QoS | None, *, envelope: bool) -> Reader:
        name = channel.name
        effective = self.qos_of(name, qos)
        edges = self._in.get((name, node), ())
        assert self.plan is not None
        remote = sorted({self.plan.process_of(e.publisher) for e in edges if e.transport == "shm"})
        parts: list[Reader] = []
        if any(edge.transport == "inproc" for edge in edges):
            parts.append(self._inproc_topic(name, effective).open_reader(node, wake))
        if remote:
            slot = channel.subscribers.index(node)
            parts.append(self._domain().open_reader(name, remote, effective,
                                                    self._codec(typename, envelope), slot, wake, node))
        other_hosts = sorted({self.plan.host_of(e.publisher) for e in edges if e.transport == "dds"})
        if other_hosts:
            topics = [edge_topic(self.plan.name, host, name) for host in other_hosts]
            remote_reader = DdsEdgeReader(self._dds_domain(), topics, self._codec(typename, envelope), effective, wake)
            with self._lock:
                self._dds_readers.append((f"{name} from {', '.join(other_hosts)}", remote_reader))
            parts.append(remote_reader)
        return parts[0] if len(parts) == 1 else _MergedReader(parts)

    def linger(self) -> list[str]:
        """Keep this process' reliable writers until their subscribers have taken what was
        published (the process' nodes have all returned); what was given up, as error lines
        naming topic, subscriber and count. Ends at once when the graph stops."""
        with self._lock:
            domain = self._shm
            dds_writers = dict(self._dds_writers)
        lost: list[str] = []
        if domain is not None:
            for miss in domain.linger(self.stop):
                channel = self.plan.channels.get(miss.topic) if self.plan is not None else None
                subscriber = (channel.subscribers[miss.slot] if channel is not None
                              and miss.slot < len(channel.subscribers) else f"slot {miss.slot}")
                lost.append(
                    f"reliable topic {miss.topic}: subscriber {subscriber!r} (pid {miss.pid}) took nothing "
                    f"for publish_timeout and has {miss.count} message(s) of this process left to take; "
                    "they are lost as this process ends (make the subscriber take them, or raise "
                    f"topics.{miss.topic}.publish_timeout)")
        for name, writer in dds_writers.items():
            if not writer.linger(self.stop):
                lost.append(f"reliable topic {name}: a subscriber on another host did not acknowledge "
                            f"every message within publish_timeout; the rest may be lost as this process ends")
        return lost

    def close(self) -> None:
        self.shutdown()
        self._close_prepared(None)
        with self._lock:
            domain, self._shm = self._shm, None
            ros1, self._ros1 = self._ros1, None
            dds, self._dds = self._dds, None
            writers, self._dds_writers = self._dds_writers, {}
            readers, self._dds_readers = self._dds_readers, []
        for name, dds_writer in writers.items():
            log.info("dds: sent %d samples of %s to other hosts", dds_writer.sent, name)
        for what, dds_reader in readers:
            log.info("dds: received %d samples of %s", dds_reader.received, what)
        if domain is not None:
            domain.close()
        if ros1 is not None:
            ros1.close()
        if dds is not None:
            dds.close()


class _Ros1Nodes:
    """The ROS 1 presence of this process' ``kind: ros1`` nodes: one ROS 1 node (slave API,
    TCPROS server) per hetros node, registered with the plan's master under ``/<node>``."""


    def __init__(self, plan: Plan, types: TypeRegistry, stop: threading.Event) -> None:
        self._plan = plan
        self._types = types
        self._stop = stop
        self._lock = threading.Lock()
        self._peers: dict[str, Ros1Peer] = {}
        self._servers: dict[tuple[str, str], Ros1ServiceServer] = {}
        self._callers: dict[tuple[str, str], Ros1ServiceCaller] = {}
        self._waiters: dict[str, SocketWaiter] = {}

    def waiter(self, node: str) -> SocketWaiter:
        """What ``node``'s executor waits on: its subscriptions' connections and in-process wake-ups."""
        with self._lock:
            waiter = self._waiters.get(node)
            if waiter is None:
                waiter = self._waiters[node] = SocketWaiter()
            return waiter

    def _peer(self, node: str) -> Ros1Peer:
        with self._lock:
            peer = self._peers.get(node)
            if peer is None:
                peer = Ros1Peer(node, self._plan.ros1_master, self._plan.ros1_host, self._stop)
                self._peers[node] = peer
            return peer

    def _declared(self, node: str, section: str, name: str) -> str:
        spec = self._plan.nodes[node]
        table: dict[str, str] = getattr(spec, section)
        if name not in table:
            raise UndeclaredEndpointError(
                f"ROS 1 node {node!r} creates a {section} endpoint on {name!r} that the project file "
                f"does not declare: add it under nodes.{node}.{section}"
            )
        return table[name]

    def _qos(self, topic: str) -> QoS:
        return self._plan.ros1_qos.get(topic, DEFAULT_QOS)

    def _caller(self, node: str, service: str) -> Ros1ServiceCaller:
        typename = self._declared(node, "clients", service)
        with self._lock:
            caller = self._callers.get((node, service))
        if caller is None:
            caller = Ros1ServiceCaller(self._peer(node), service, Ros1ServiceType(self._types, typename),
                                       SERVICE_QOS)
            with self._lock:
                caller = self._callers.setdefault((node, service), caller)
        return caller

    def open_writer(self, name: str, node: str, *, envelope: bool) -> Writer:
        if not envelope:
            typename = self._declared(node, "publish", name)
            qos = self._qos(name)
            return Ros1Writer(self._peer(node).advertise(name, Ros1Type(self._types, typename),
                                                         latch=qos.keeps_history, qos=qos))
        service, client = service_of(name)
        if client:
            server = self._servers.get((node, service))
            if server is None:
                raise UndeclaredEndpointError(f"ROS 1 node {node!r} replies on {service}, which it does not serve")
            return server.writer
        return self._caller(node, service).writer

    def open_reader(self, name: str, node: str, wake: Wake, *, envelope: bool) -> Reader:
        if not envelope:
            typename = self._declared(node, "subscribe", name)
            kind = Ros1Type(self._types, typename)
            return open_ros1_reader(self._peer(node), name, kind, self._qos(name), self.waiter(node), wake)
        service, client = service_of(name)
        if not client:
            kind_name = self._declared(node, "services", service)
            server = Ros1ServiceServer(self._peer(node), service, Ros1ServiceType(self._types, kind_name),
                                       SERVICE_QOS, wake, self._stop)
            self._servers[(node, service)] = server
            return server.reader
        return self._caller(node, service).attach(wake)

    def close(self) -> None:
        with self._lock:
            callers, self._callers = list(self._callers.values()), {}
            peers, self._peers = list(self._peers.values()), {}
            waiters, self._waiters = list(self._waiters.values()), {}
        for caller in callers:
            caller.close()
        for peer in peers:
            peer.close()
        for waiter in waiters:
            waiter.close()
