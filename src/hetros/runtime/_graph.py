"""One process' share of the graph: the transports its nodes' endpoints use.

For each endpoint the plan names the transport of every edge: peers in this process (inproc),
in other processes of this host (shm), on other hosts (dds), or, for a ``kind: ros1`` node,
whatever the ROS 1 master knows (tcpros). The graph looks each kind up in the transport
registry and opens through it; it never names a transport. A writer feeds all of an
endpoint's transports; a reader drains them all.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

from .._errors import UndeclaredEndpointError
from .._log import get_logger
from .._qos import DEFAULT_QOS, QoS
from ..msg import TypeRegistry, registry
from ..plan import LAUNCHER, ROS1_TRANSPORT, TRANSPORT_ORDER, ChannelPlan, EdgePlan, Plan
from ..transport import (
    Codec,
    Endpoint,
    EnvelopeCodec,
    MessageCodec,
    Reader,
    Transport,
    TransportContext,
    WaitSource,
    Wake,
    Writer,
    transport_class,
)
from ._clock import Clock, SimulatedClock
from ._endpoints import EndpointWriter, MergedReader, Relay, RetainedReader, endpoint_writer
from ._matched import Matches
from ._taps import TapPoint

if TYPE_CHECKING:
    from ._node import Node

log = get_logger("hetros.graph")
# the transport of a graph without a project (everything in this process)
_STANDALONE = "inproc"


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
        self._adhoc_qos: dict[str, QoS] = {}
        self._qos_told: set[str] = set()  # topics whose code asked for another QoS, told once each
        self._codecs: dict[tuple[str, bool], Codec] = {}
        self._stop_hooks: list[Callable[[], None]] = []
        # set by a launch's worker: tells the launcher this process has shutdown hooks (``on_shutdown``)
        self.announce_hooks: Callable[[], None] | None = None
        self._prepared: dict[tuple[str, str], RetainedReader] = {}
        self._transports: dict[str, Transport] = {}
        self._context = TransportContext(plan, process, session, self.stop, self.types, self._codec)
        # wall time, or /clock's with use_sim_time: what every node of this process reads
        self.clock: Clock = SimulatedClock(self.stop) if plan is not None and plan.use_sim_time else Clock()
        # what a look from outside finds (``launch._control``): the live nodes, the topics' taps
        self.nodes: dict[str, Node] = {}
        self._taps: dict[str, TapPoint] = {}
        self._subscriber_taps: set[str] = set()
        # the endpoints matched to each other (matched events, ``get_subscription_count``)
        self.matches = Matches(plan, process)

    def transport(self, kind: str) -> Transport:
        """This process' transport for edges of ``kind``, opened (and its module imported) on first use."""
        with self._lock:
            found = self._transports.get(kind)
        if found is not None:
            return found
        made = transport_class(kind)(self._context)
        with self._lock:
            found = self._transports.setdefault(kind, made)
        if found is not made:
            made.close()
        return found

    def _opened(self) -> list[Transport]:
        with self._lock:
            return list(self._transports.values())

    def prepare(self, nodes: list[str]) -> None:
        """Open every declared subscription of ``nodes`` now (static initialisation).

        Messages published before a node's code reaches ``create_subscription``
        wait in its FIFO instead of being lost to start-up order.
        """
        assert self.plan is not None
        for node in nodes:
            for name, typename, envelope in self.plan.inputs(node):
                relay = Relay()
                reader = self._open_reader(name, node, typename, relay, self._declared_qos(name), envelope)
                self._prepared[(name, node)] = RetainedReader(reader, relay, self._give_back(name, node))
        for kind in self.plan.transports_of(nodes):
            self.transport(kind).prepare(nodes)
        for channel in self.plan.channels.values():
            # taps exist from the start, so a look (launch --record) can attach before the first publish
            if channel.kind == "topic" and self.process in self.plan.tap_sites(channel.name)[1]:
                self.tap_point(channel.name, channel.type)

    def spins(self, node: str) -> None:
        """``node``'s code began to spin: the readers kept for it from start-up that no subscription
        claimed stop holding messages for it (``RetainedReader.lapse``)."""
        with self._lock:
            unclaimed = [(name, reader) for (name, owner), reader in self._prepared.items() if owner == node]
        for name, reader in unclaimed:
            reader.lapse(self._declared_qos(name).depth)

    def _give_back(self, channel: str, node: str) -> Callable[[RetainedReader], None]:
        def release(reader: RetainedReader) -> None:
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
        """What ``node``'s executor blocks on besides its condition (a transport's wake channel,
        a ROS 1 node's connections), or None when every reader wakes it through the condition."""
        if self.plan is None:
            return None
        sources = [source for kind in self.plan.transports_of([node])
                   if (source := self.transport(kind).wait_source(node)) is not None]
        if len(sources) > 1:
            raise UndeclaredEndpointError(
                f"node {node!r} would wait on {len(sources)} transports' wake channels at once; a node "
                "reads either through ROS 1 or through hetros' own transports")
        return sources[0] if sources else None

    def on_stop(self, hook: Callable[[], None]) -> None:
        """Call ``hook`` once when the graph stops (executors and blocked takes wake up); at once if it has."""
        with self._lock:
            stopped = self.stop.is_set()
            if not stopped:
                self._stop_hooks.append(hook)
        if stopped:
            hook()

    def on_shutdown(self, hook: Callable[[], None]) -> None:
        """A node's own shutdown hook (rospy's ``on_shutdown``): ``on_stop``, and the launcher is told once
        (``announce_hooks``), so that it stops this process before the ones it publishes to, which then
        still hear what the hook publishes."""
        self.on_stop(hook)
        announce, self.announce_hooks = self.announce_hooks, None
        if announce is not None:
            announce()

    def shutdown(self) -> None:
        """Stop every node of this process: set the stop flag and wake everything waiting. Each hook runs
        once, however often the graph is told to stop (a stop request, then the close of the process)."""
        self.stop.set()
        with self._lock:
            hooks, self._stop_hooks = self._stop_hooks, []
        for hook in hooks:
            hook()

    @classmethod
    def standalone(cls) -> Graph:
        """A graph with no project: every endpoint allowed, everything in-process."""
        return cls(None)

    # -- what a look from outside finds ----------------------------------------------------

    def tap_point(self, topic: str, typename: str) -> TapPoint:
        """The one tap of ``topic`` in this process, shared by its publishers here."""
        point = self._taps.get(topic)
        if point is None:
            with self._lock:
                qos = self._declared_qos(topic) if self.plan is not None else None
                history = qos.depth if qos is not None and qos.keeps_history else 0
                point = self._taps.setdefault(topic, TapPoint(topic, typename, history))
        return point

    def subscriber_tap(self, topic: str, typename: str) -> TapPoint | None:
        """The tap a subscription feeds when no process of this host publishes ``topic`` (it comes from
        a ROS peer or another host) and this process is where the plan looks at it; else None."""
        plan = self.plan
        if plan is None or topic not in plan.channels or plan.channels[topic].kind != "topic":
            return None
        role, sites = plan.tap_sites(topic)
        if role != "subscribe" or self.process not in sites:
            return None
        with self._lock:
            if topic in self._subscriber_taps:
                return None  # a second subscription here: the first one counts
            self._subscriber_taps.add(topic)
        return self.tap_point(topic, typename)

    def taps(self) -> dict[str, TapPoint]:
        with self._lock:
            return dict(self._taps)

    def node_started(self, node: Node) -> None:
        with self._lock:
            self.nodes[node.name] = node

    def node_closed(self, node: Node) -> None:
        with self._lock:
            if self.nodes.get(node.name) is node:
                del self.nodes[node.name]

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
            channel = self.plan.channels[name]
            declared = channel.qos
            if requested is not None and not channel.qos_given:
                # the endpoint's own: a deadline it watches (deadline_of), the policies it is matched by
                # (endpoint_qos); a stronger reliability than asked loses nothing the code expects
                requested = replace(requested, deadline=declared.deadline, reliability=declared.reliability,
                                    liveliness=declared.liveliness, lease_duration=declared.lease_duration)
                if requested.history == "keep_last" and declared.history == "keep_all":
                    # ROS code's plain depth (``create_publisher(T, name, 10)``) asks for no policy: hetros's
                    # default keeps every message of a reliable topic, which loses nothing the code expects
                    requested = replace(requested, history=declared.history)
                # a lifespan is the endpoint's own (a writer's messages expire by it), shaping no transport;
                # a durability is served per subscription by the reader kept from start-up (join_late)
                declared = replace(declared, lifespan=requested.lifespan)
                requested = replace(requested, durability=declared.durability)
            if requested is not None and requested != declared and name not in self._qos_told:
                self._qos_told.add(name)
                log.warning("%s: the code asks for %s but the project file's QoS applies: %s "
                            "(change it under topics.%s)", name, requested, declared, name)
            return declared
        with self._lock:
            return self._adhoc_qos.setdefault(name, requested or DEFAULT_QOS)

    def endpoint_qos(self, name: str, requested: QoS | None) -> QoS:
        """What one endpoint offers or requests, as ROS 2 matches endpoints: its code's QoS where the
        project file gives the topic none, else the topic's (``qos_of``)."""
        channel = self.plan.channels.get(name) if self.plan is not None else None
        if requested is not None and (channel is None or not channel.qos_given):
            return requested
        return self.qos_of(name, None)

    def deadline_of(self, name: str, requested: QoS | None) -> float | None:
        """The deadline an endpoint of ``name`` watches: the project file's where it sets the topic's QoS,
        else the one the endpoint asked for (it shapes no transport: every endpoint may have its own)."""
        channel = self.plan.channels.get(name) if self.plan is not None else None
        if channel is not None and not channel.qos_given and requested is not None:
            return requested.deadline
        return self.qos_of(name, None).deadline

    def _declared_qos(self, name: str) -> QoS:
        """The QoS of a channel the plan declares (a ROS 1 node's topics are the ROS 1 side's)."""
        assert self.plan is not None
        channel = self.plan.channels.get(name)
        return channel.qos if channel is not None else self.plan.ros1_qos.get(name, DEFAULT_QOS)

    def _codec(self, typename: str, envelope: bool) -> Codec:
        key = (typename, envelope)
        codec = self._codecs.get(key)
        if codec is None:
            inner = MessageCodec(self.types, typename)
            codec = EnvelopeCodec(inner) if envelope else inner
            self._codecs[key] = codec
        return codec

    def _speaks_ros1(self, node: str) -> bool:
        return self.plan is not None and node in self.plan.nodes and self.plan.speaks_ros1(node)

    # -- endpoints -------------------------------------------------------------------------

    def _by_transport(self, name: str, node: str, role: str) -> dict[str, tuple[EdgePlan, ...]]:
        """``node``'s endpoint on ``name`` split by the transport of its edges (a ROS 1 node's
        all go to tcpros)."""
        assert self.plan is not None
        if self.plan.speaks_ros1(node):
            return {ROS1_TRANSPORT: ()}
        split: dict[str, list[EdgePlan]] = {}
        for edge in self.plan.edges_of(name, node, "publish" if role == "publish" else "subscribe"):
            split.setdefault(edge.transport, []).append(edge)
        def nearest_first(kind: str) -> int:
            return TRANSPORT_ORDER.index(kind) if kind in TRANSPORT_ORDER else len(TRANSPORT_ORDER)

        return {kind: tuple(split[kind]) for kind in sorted(split, key=nearest_first)}

    def open_writer(self, name: str, node: str, typename: str, *, qos: QoS | None = None,
                    envelope: bool = False) -> EndpointWriter:
        if not self._speaks_ros1(node) and self.channel(name, node, "publish") is None:
            endpoint = Endpoint(name, node, typename, self.qos_of(name, qos), envelope)
            return endpoint_writer([self.transport(_STANDALONE).open_writer(endpoint)], self.types)
        effective = self._declared_qos(name) if self._speaks_ros1(node) else self.qos_of(name, qos)
        parts: list[Writer] = []
        for kind, edges in self._by_transport(name, node, "publish").items():
            parts.append(self.transport(kind).open_writer(Endpoint(name, node, typename, effective, envelope, edges)))
        return endpoint_writer(parts, self.types)

    def open_reader(self, name: str, node: str, typename: str, wake: Wake, *,
                    qos: QoS | None = None, envelope: bool = False, late: bool = False) -> Reader:
        """``node``'s reader of ``name``: the one opened at start-up where there is one, so that nothing
        published before the code subscribed is lost to start-up order; ``late`` (the node already
        spins) keeps of that only what a late joiner gets (``RetainedReader.join_late``)."""
        if not self._speaks_ros1(node) and self.channel(name, node, "subscribe") is None:
            endpoint = Endpoint(name, node, typename, self.qos_of(name, qos), envelope)
            return self.transport(_STANDALONE).open_reader(endpoint, wake)
        with self._lock:
            prepared = self._prepared.pop((name, node), None)
        if prepared is not None:
            if late:
                prepared.join_late(self.endpoint_qos(name, qos))
            prepared.relay.target = wake
            wake()
            return prepared
        effective = self._declared_qos(name) if self._speaks_ros1(node) else self.qos_of(name, qos)
        return self._open_reader(name, node, typename, wake, effective, envelope)

    def _open_reader(self, name: str, node: str, typename: str, wake: Wake, qos: QoS, envelope: bool) -> Reader:
        parts = [self.transport(kind).open_reader(Endpoint(name, node, typename, qos, envelope, edges), wake)
                 for kind, edges in self._by_transport(name, node, "subscribe").items()]
        return parts[0] if len(parts) == 1 else MergedReader(parts)

    def wait_for_remote_readers(self, timeout: float = 10.0) -> list[str]:
        """Wait until each writer to other hosts is matched by every remote reader the plan has for it,
        so nothing reliable is published before its remote subscribers hear it; return the channels
        still short when ``timeout`` passed (they are logged)."""
        return [name for transport in self._opened() for name in transport.wait_matched(timeout)]

    def linger(self) -> list[str]:
        """Keep this process' reliable writers until their subscribers have taken what was
        published (the process' nodes have all returned); what was given up, as error lines
        naming topic, subscriber and count. Ends at once when the graph stops."""
        return [line for transport in self._opened() for line in transport.linger()]

    def close(self) -> None:
        self.shutdown()
        self.clock.close()
        self._close_prepared(None)
        with self._lock:
            transports, self._transports = self._transports, {}
        for transport in transports.values():
            transport.close()
