"""The node API: rclpy's shape, one meaning on every mapping.

A node is written once and runs unchanged as a thread, as a process pinned to
a core, or (later) beside hardware: it never names a transport. Messages it
receives are read-only and may be the publisher's very object (zero copies in
a process); ``msg.copy()`` keeps a writable one.
"""

from __future__ import annotations

import itertools
import logging
import os
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from typing import TYPE_CHECKING, Any, TypeVar

from .._errors import (
    NodeError,
    ParameterError,
    TopicTypeError,
)
from .._qos import QoS
from ..msg import ActionKind, Message, ServiceKind, ServiceType, service_type
from ..plan import ROS1_TRANSPORT, NodePlan, request_channel, resolve_name
from ._clock import Clock, SimulatedTimer, Ticker, check_hz, check_period
from ._endpoints import Relay, TopicReaders
from ._entities import Client, HandlingStats, Publisher, Service, Subscription, Timer, typename_of
from ._executor import Executor
from ._graph import Graph
from ._log import node_logger
from ._matched import IncompatibleQosStatus, MatchedStatus, MatchedWatch
from ._parameters import ParameterAccess, ParameterServices, ProjectParameters, type_change_problem
from ._qos_events import (
    DeadlineMissedStatus,
    LivelinessChangedStatus,
    LivelinessLostStatus,
    LivelinessLostWatch,
    LivelinessWatch,
    MessageLostStatus,
    MessageLostWatch,
    WatchedReader,
    watch_deadline,
)

if TYPE_CHECKING:
    from ..transport import Reader
    from ._action import ActionClient, ActionServer, ServerGoalHandle
    from ._lifecycle import Lifecycle, TransitionCallback

M = TypeVar("M", bound=Message)
# set (to 1) in the launcher's environment by `hetros launch --node-times`; workers inherit it
NODE_TIMES_VARIABLE = "HETROS_NODE_TIMES"
_MISSING: Any = object()



class Node:
    """What a node function receives: endpoints, timers, parameters, a logger."""

    def __init__(self, name: str, graph: Graph | None = None,
                 parameters: dict[str, Any] | None = None) -> None:
        self.name = name
        self.graph = graph or Graph.standalone()
        self.log = node_logger(name)
        self.executor = Executor(self.graph.stop, self.graph.wake_source(name))
        self.graph.on_stop(self.executor.wake)
        self._parameters = dict(parameters or {})
        if self.graph.plan is not None and name in self.graph.plan.nodes and parameters is None:
            self._parameters = dict(self.graph.plan.nodes[name].parameters)
        # what the node's parameter services read and set: an rclpy node puts its own in (its callbacks)
        self.parameter_access: ParameterAccess = ProjectParameters(self)
        self._parameter_services: ParameterServices | None = None
        # ROS nodes the code made beside the project's one (rclpy's Node('other') in the same main), by
        # full name: each answers its own parameter services, and `hetros node list` and `param` find it
        self._guests: dict[str, ParameterServices] = {}
        self._closables: list[Publisher[Any] | Subscription[Any] | Service | Client | ActionServer
                              | ActionClient] = []
        self.clients: dict[str, Client] = {}
        self.action_servers: dict[str, ActionServer] = {}
        # each topic's transport reader, shared by this node's subscriptions to it (``_topic_reader``)
        self._topic_readers: dict[str, TopicReaders] = {}
        self._first_subscription: dict[str, Subscription[Any]] = {}
        # set when the node raised and the graph will stop for it: what it leaves unfinished is
        # then explained by the graph's stop reason rather than answered
        self.failing = False
        self._spun = False
        # the subscription whose message a take loop works on now, and since when (its node time)
        self.taken_by: Subscription[Any] | None = None
        self.taken_at = 0.0
        self.taken_cpu = 0.0
        # while profiling (``HETROS_PROFILE``): the topic whose callback runs now, and per (input, output)
        # topic how many messages the node published while handling that input ("" for timers and loops)
        self.handling: str | None = None
        self.triggers: dict[tuple[str, str], int] = {}
        self.in_period = False  # a rate's period began since the last take: what it publishes, the period caused
        self.action_clients: dict[str, ActionClient] = {}
        # what the node's own figures are for ``hetros top`` (a gateway's cycles per message), when it has any
        self.figures: Callable[[], dict[str, Any]] | None = None
        # a managed node's state machine, once its code made it one (``create_lifecycle``, rclpy.lifecycle)
        self.lifecycle: Lifecycle | None = None
        # the traceback of a thread the node's code started that raised: the node fails with it
        self.thread_failure: str | None = None
        planned_services = planned.services if (planned := self._planned()) is not None else {}
        for service, (srv_type, handler) in self.parameter_services.items():
            if service in planned_services:
                self.create_service(srv_type, service, handler)  # another node's parameter client calls it
        self.graph.node_started(self)

    # -- endpoints -------------------------------------------------------------------------

    @property
    def namespace(self) -> str:
        """The node's namespace from the project file ("" at the root)."""
        planned = self._planned()
        return planned.namespace if planned is not None else ""

    @property
    def ros_name(self) -> str:
        """The name the project file gives the node in ROS (``name:``); "" when it gives none, so that the
        name its code gives (rclpy's ``Node('talker')``) stands."""
        planned = self._planned()
        return planned.ros_name if planned is not None else ""

    def _planned(self) -> NodePlan | None:
        plan = self.graph.plan
        return plan.nodes.get(self.name) if plan is not None else None

    def resolve_name(self, name: str, namespace: str | None = None, node_name: str | None = None) -> str:
        """A topic, service or action name as ROS resolves it for this node: ``chatter`` under its
        namespace, ``~/x`` under its name, then its remaps (all from the project file)."""
        planned = self._planned()
        return resolve_name(name, self.namespace if namespace is None else namespace,
                            node_name or self.ros_name or self.name, planned.remap if planned is not None else None)

    def create_publisher(self, msg_type: type[M], topic: str, *, qos: QoS | None = None,
                         on_deadline_missed: Callable[[DeadlineMissedStatus], object] | None = None,
                         on_matched: Callable[[MatchedStatus], object] | None = None,
                         on_incompatible_qos: Callable[[IncompatibleQosStatus], object] | None = None,
                         on_liveliness_lost: Callable[[LivelinessLostStatus], object] | None = None
                         ) -> Publisher[M]:
        """``on_deadline_missed(status)`` runs in this node's executor when the topic has a
        ``deadline`` and this publisher let a period pass without publishing; ``on_matched(status)``
        when subscriptions to its topic come or go (see ``MatchedStatus``); ``on_incompatible_qos(status)``
        when one requests more than this publisher's ``qos`` offers; ``on_liveliness_lost(status)`` when a
        ``manual_by_topic`` publisher let its ``lease_duration`` pass without publishing or asserting."""
        typename = typename_of(msg_type)
        topic = self.resolve_name(topic)
        self._check_declared_type(topic, typename)
        writer = self.graph.open_writer(topic, self.name, typename, qos=qos)
        publisher = Publisher(self, msg_type, topic, writer)
        effective = self.graph.qos_of(topic, None)
        publisher.deadline = watch_deadline(self, f"publisher of {topic} in {self.name}",
                                            self.graph.deadline_of(topic, qos), on_deadline_missed)
        offered = self.graph.endpoint_qos(topic, qos)
        publisher.manual_liveliness = "manual_by_topic" in (effective.liveliness, offered.liveliness)
        if on_liveliness_lost is not None and offered.liveliness == "manual_by_topic" and \
                offered.lease_duration is not None:
            publisher.liveliness_lost = LivelinessLostWatch(self, offered.lease_duration, on_liveliness_lost)
        if publisher.manual_liveliness:
            writer.assert_liveliness()  # alive from its creation, as a ROS 2 publisher
        publisher.matched = MatchedWatch(self, offered, on_matched, on_incompatible_qos)
        self.graph.matches.joined(topic, "publish", publisher.matched)
        self._closables.append(publisher)
        return publisher

    def create_subscription(self, msg_type: type[M], topic: str,
                            callback: Callable[[M], object] | None = None, *,
                            qos: QoS | None = None,
                            on_deadline_missed: Callable[[DeadlineMissedStatus], object] | None = None,
                            on_liveliness_changed: Callable[[LivelinessChangedStatus], object] | None = None,
                            on_message_lost: Callable[[MessageLostStatus], object] | None = None,
                            on_matched: Callable[[MatchedStatus], object] | None = None,
                            on_incompatible_qos: Callable[[IncompatibleQosStatus], object] | None = None
                            ) -> Subscription[M]:
        """``on_deadline_missed(status)`` runs in this node's executor when the topic has a
        ``deadline`` and a period passed without a message for this subscription;
        ``on_liveliness_changed(status)`` when a publisher it hears from becomes alive or not
        alive (a process that ended; a ``manual_by_topic`` publisher silent past its lease);
        ``on_message_lost(status)`` when messages were lost to it (keep_last overwrote them, a lifespan
        expired them, best_effort dropped them); ``on_matched(status)`` when publishers of its topic
        come or go; ``on_incompatible_qos(status)`` when one offers less than this subscription's ``qos``
        requests (it hears nothing from such a publisher)."""
        typename = typename_of(msg_type)
        topic = self.resolve_name(topic)
        self._check_declared_type(topic, typename)
        subscription = Subscription(self, msg_type, topic, callback)
        if callback is not None:
            self.executor.entities += 1
            self.executor.poll_while_spinning(subscription)
        reader = self._topic_reader(subscription, typename, qos)
        effective = self.graph.qos_of(topic, None)  # after opening: the first opener's QoS is an ad-hoc topic's
        watch = watch_deadline(self, f"subscription to {topic} in {self.name}", self.graph.deadline_of(topic, qos),
                               on_deadline_missed)
        subscription._watch = watch
        subscription._attach(reader if watch is None else WatchedReader(reader, watch))
        if on_liveliness_changed is not None or effective.liveliness == "manual_by_topic" or \
                effective.lease_duration is not None:
            subscription.liveliness = LivelinessWatch(self, f"subscription to {topic} in {self.name}", reader,
                                                      effective.lease_duration, on_liveliness_changed)
        if on_message_lost is not None:
            subscription.message_lost = MessageLostWatch(self, reader, on_message_lost)
        subscription.matched = MatchedWatch(self, self.graph.endpoint_qos(topic, qos), on_matched, on_incompatible_qos,
                                            subscription._deafen)
        self.graph.matches.joined(topic, "subscribe", subscription.matched)
        self._closables.append(subscription)
        return subscription

    def _topic_reader(self, subscription: Subscription[Any], typename: str, qos: QoS | None) -> Reader:
        """The reader of one more subscription to its topic: the topic's transport reader for the first,
        branches of it once there are two (every subscription gets every message, as in ROS)."""
        topic = subscription.topic
        shared = self._topic_readers.get(topic)
        if shared is None or shared.closed:
            relay = Relay()
            relay.target = subscription._on_wake  # before opening: a reader with messages waiting wakes at once
            inner = self.graph.open_reader(topic, self.name, typename, relay, qos=qos, late=self.spun)
            shared = TopicReaders(inner, relay, lambda: self._forget_topic(topic))
            self._topic_readers[topic] = shared
            self._first_subscription[topic] = subscription
            return shared.sole()
        effective = self.graph.qos_of(topic, qos)
        first = self._first_subscription.pop(topic, None)
        if first is not None and first._reader is not None:  # the first one becomes a branch too
            first._rebase(shared.branch(first._on_wake, self.graph.qos_of(topic, None)))
        return shared.branch(subscription._on_wake, effective)

    def _forget_topic(self, topic: str) -> None:
        """Every subscription to ``topic`` closed: a later one opens the topic afresh."""
        self._topic_readers.pop(topic, None)
        self._first_subscription.pop(topic, None)

    def create_service(self, srv_type: ServiceKind, name: str, handler: Callable[[Any], Any]) -> Service:
        srv_type = service_type(srv_type)
        name = self.resolve_name(name)
        self._check_declared_type(request_channel(name), typename_of(srv_type.Request))
        service = Service(self, srv_type, name, handler)
        self.executor.entities += 1
        self._closables.append(service)
        return service

    def create_client(self, srv_type: ServiceKind, name: str) -> Client:
        srv_type = service_type(srv_type)
        name = self.resolve_name(name)
        if name in self.clients:
            raise NodeError(f"node {self.name!r} already has a client of {name}; reuse it")
        self._check_declared_type(request_channel(name), typename_of(srv_type.Request))
        client = Client(self, srv_type, name)
        self.clients[name] = client
        self._closables.append(client)
        return client

    def create_action_server(self, action_type: ActionKind, name: str,
                             execute: Callable[[ServerGoalHandle], Any] | None = None, *,
                             goal_callback: Callable[[Any], bool] | None = None,
                             cancel_callback: Callable[[ServerGoalHandle], bool] | None = None,
                             max_goals: int | None = None) -> ActionServer:
        """Serve an action; without ``execute`` the node takes goals itself (``server.take_goal()``).

        ``goal_callback(goal)`` and ``cancel_callback(goal_handle)`` decide whether to accept
        (both accept everything by default); ``max_goals`` (else the project file's, else 8)
        bounds how many ``execute`` calls run at once.
        """
        from ._action import ActionServer

        name = self.resolve_name(name)
        if name in self.action_servers:
            raise NodeError(f"node {self.name!r} already serves action {name}")
        server = ActionServer(self, action_type, name, execute, goal_callback=goal_callback,
                              cancel_callback=cancel_callback, max_goals=max_goals)
        self.executor.entities += 1
        self.action_servers[name] = server
        self._closables.append(server)
        return server

    def create_action_client(self, action_type: ActionKind, name: str) -> ActionClient:
        from ._action import ActionClient

        name = self.resolve_name(name)
        if name in self.action_clients:
            raise NodeError(f"node {self.name!r} already has a client of action {name}; reuse it")
        client = ActionClient(self, action_type, name)
        self.action_clients[name] = client
        self._closables.append(client)
        return client

    def create_timer(self, period: float, callback: Callable[[], object]) -> Timer | SimulatedTimer:
        """Call ``callback`` every ``period`` seconds of the graph's clock (simulated time with
        ``use_sim_time``), from this node's executor."""
        clock = self.graph.clock
        if clock.simulated:
            check_period(period, "a timer's period")
            self.executor.entities += 1
            return SimulatedTimer(clock, self.executor, period, callback)
        self.executor.entities += 1
        return Timer(self, period, callback)

    def get_clock(self) -> Clock:
        """The graph's clock: ``now()`` is wall time, or the time on /clock with ``use_sim_time``."""
        return self.graph.clock

    def _check_declared_type(self, channel: str, typename: str) -> None:
        plan = self.graph.plan
        if plan is None or channel not in plan.channels:
            return
        declared = plan.channels[channel].type
        if declared != typename:
            raise TopicTypeError(
                f"node {self.name!r} uses {channel} with type {typename}, but the project declares "
                f"{declared}; make the code and nodes.{self.name} agree"
            )

    # -- time and spinning -----------------------------------------------------------------

    def ok(self) -> bool:
        return not self.graph.stop.is_set()

    def sleep(self, seconds: float) -> bool:
        """Sleep, waking early on shutdown; return whether the graph is still running."""
        return not self.graph.stop.wait(seconds)

    def rate(self, hz: float) -> Iterator[int]:
        """Yield 0, 1, 2, ... at ``hz`` until shutdown (ends cleanly, no exception)."""
        period = 1.0 / check_hz(hz, "rate(hz)")
        clock = self.graph.clock
        if clock.simulated:
            yield from self._simulated_rate(clock, int(period * 1e9))
            return
        due = time.monotonic()
        for tick in itertools.count():
            if self.graph.stop.is_set():
                return
            self.period_began()
            yield tick
            due += period
            delay = due - time.monotonic()
            if delay < -period:
                due = time.monotonic()
                delay = 0.0
            if delay > 0 and self.graph.stop.wait(delay):
                return

    def _simulated_rate(self, clock: Clock, period_ns: int) -> Iterator[int]:
        ticker = Ticker(clock, period_ns)
        for tick in itertools.count():
            if self.graph.stop.is_set():
                return
            self.period_began()
            yield tick
            if not ticker.sleep(self.graph.stop):
                return

    @property
    def spun(self) -> bool:
        """Whether the node's own code spun its executor (else a function that returns is spun for it);
        a subscription made after that joins late (``Graph.open_reader``)."""
        return self._spun

    @spun.setter
    def spun(self, value: bool) -> None:
        if value and not self._spun:
            self._spun = True
            self.graph.spins(self.name)

    def spin(self, timeout: float | None = None) -> None:
        """Run this node's callbacks, one at a time, until shutdown (or ``timeout``)."""
        self.spun = True
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self.graph.stop.is_set():
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                return
            self.executor.spin_once(left)

    def spin_once(self, timeout: float | None = None) -> bool:
        if not self._spun:  # the setter's work is once per node, not once per callback
            self.spun = True
        return self.executor.spin_once(timeout)

    # -- parameters ------------------------------------------------------------------------

    def get_parameter(self, name: str, default: Any = _MISSING) -> Any:
        """The project file's parameter ``name``; else, with ``external: ros1:``, the ROS 1 parameter
        server's (``/global``, ``relative`` to ``/``, ``~private`` to this node); else ``default``."""
        if name in self._parameters:
            return self._parameters[name]
        master = self.graph.plan.ros1_master if self.graph.plan is not None else ""
        if master:
            try:
                return self.graph.transport(ROS1_TRANSPORT).parameter(self.name, name)
            except KeyError:
                pass
        if default is not _MISSING:
            return default
        elsewhere = f" nor on the ROS 1 parameter server at {master}" if master else ""
        raise ParameterError(
            f"node {self.name!r} has no parameter {name!r}{elsewhere}: declare it under "
            f"nodes.{self.name}.parameters.{name} in the project file, or pass a default"
        )

    @property
    def parameters(self) -> dict[str, Any]:
        return dict(self._parameters)

    def set_parameter(self, name: str, value: Any) -> None:
        """Change a parameter while the node runs (``hetros param set``); ``get_parameter`` returns the
        new value from then on. A parameter keeps its type, as ROS 2's do: an integer may become a
        float, nothing else changes kind."""
        if name in self._parameters:
            old = self._parameters[name]
            if problem := type_change_problem(self.name, name, old, value):
                raise ParameterError(f"{problem} ({value!r}): give a value of its type")
            if isinstance(old, float):
                value = float(value)
        self._parameters = {**self._parameters, name: value}

    def store_parameter(self, name: str, value: Any) -> None:
        """Set a parameter whatever its type was: for an API whose own rules have passed the change (an
        rclpy parameter declared dynamically typed)."""
        self._parameters = {**self._parameters, name: value}

    def delete_parameter(self, name: str) -> None:
        """Forget a parameter (rospy's ``delete_param``); KeyError-free when it was never set is not ROS's:
        a parameter that does not exist raises ParameterError naming it."""
        if name not in self._parameters:
            raise ParameterError(f"node {self.name!r} has no parameter {name!r} to delete")
        self._parameters = {k: v for k, v in self._parameters.items() if k != name}

    # -- what a look from outside finds (``hetros node info``, ``top``, ``service call``) ----

    @property
    def full_name(self) -> str:
        """Namespace and name, as the plan gives them (``/r2/talker``)."""
        plan = self.graph.plan
        return plan.full_name(self.name) if plan is not None and self.name in plan.nodes else f"/{self.name}"

    @property
    def parameter_services(self) -> dict[str, tuple[ServiceType, Callable[[Any], Any]]]:
        """This node's parameter services, and those of the ROS nodes its code made beside it: name ->
        (srv type, handler), under each one's full ROS name."""
        if self._parameter_services is None:
            self._parameter_services = ParameterServices(self, self.full_name)
        found = dict(self._parameter_services.handlers)
        for guest in list(self._guests.values()):
            found.update(guest.handlers)
        return found

    def add_ros_node(self, full_name: str, access: ParameterAccess) -> None:
        """A ROS node the code made beside this one, named ``full_name``: it answers its own parameter
        services through ``access``. The node itself stays this node's: its endpoints are the plan's."""
        if full_name != self.full_name:
            self._guests[full_name] = ParameterServices(self, full_name, access)

    def remove_ros_node(self, full_name: str) -> None:
        self._guests.pop(full_name, None)

    def ros_nodes(self) -> list[str]:
        """The full ROS names this node answers to: its own, then those its code made."""
        return [self.full_name, *sorted(self._guests)]

    def create_lifecycle(self, on_configure: Callable[[], bool | None] | None = None,
                         on_activate: Callable[[], bool | None] | None = None,
                         on_deactivate: Callable[[], bool | None] | None = None,
                         on_cleanup: Callable[[], bool | None] | None = None,
                         on_shutdown: Callable[[], bool | None] | None = None,
                         on_error: Callable[[], bool | None] | None = None) -> Lifecycle:
        """Make this a managed node (ROS 2's lifecycle): each callback runs in its transition, and may
        refuse it by returning False (raising is the transition's error). ``lifecycle.state`` tells where
        the node is; ``hetros lifecycle set`` and the project's ``lifecycle:`` move it."""
        from ._lifecycle import from_functions

        run = from_functions(on_configure=on_configure, on_activate=on_activate, on_deactivate=on_deactivate,
                             on_cleanup=on_cleanup, on_shutdown=on_shutdown, on_error=on_error)
        return self.manage(run)

    def manage(self, callback: TransitionCallback, full_name: str = "") -> Lifecycle:
        """The state machine of this managed node, made once; ``callback(state, started_from)`` runs in each
        transition state and returns SUCCESS, FAILURE or ERROR (rclpy.lifecycle's nodes use this)."""
        if self.lifecycle is not None:
            raise NodeError(f"node {self.name!r} is a managed node already; make one lifecycle per node")
        from ._lifecycle import Lifecycle

        plan = self.graph.plan
        name = full_name or (plan.full_name(self.name) if plan is not None and self.name in plan.nodes
                             else f"/{self.name}")
        self.lifecycle = Lifecycle(self, name, callback)
        return self.lifecycle

    def entities(self) -> list[Any]:
        """The node's publishers, subscriptions, services, clients and actions, as created."""
        return list(self._closables)

    def unheard(self) -> list[str]:
        """The topics a node that subscribed and never received a message waited on (empty when it
        received one, or subscribed to nothing): a required consumer that ends so has seen no input."""
        subscriptions = [e for e in self._closables if hasattr(e, "received") and hasattr(e, "topic")]
        if any(s.received() for s in subscriptions):
            return []
        return sorted({s.topic for s in subscriptions})

    def period_began(self) -> None:
        """A rate loop woke for its next period (``rate``, rclpy's and rospy's ``Rate.sleep``): until the
        next take, what the node publishes is the period's doing, not the last message's."""
        self.in_period = True

    def count_publish(self, topic: str) -> None:
        """Count a publish on ``topic`` against the input the node is handling (profiling only)."""
        taken = self.taken_by
        cause = self.handling or (taken.topic if taken is not None and not self.in_period else "")
        key = (cause, topic)
        self.triggers[key] = self.triggers.get(key, 0) + 1

    def handling_stats(self) -> dict[str, HandlingStats]:
        """Per subscription and service: the node's time per message."""
        found: dict[str, HandlingStats] = {}
        for endpoint in list(self._closables):
            if isinstance(endpoint, Subscription):
                found[endpoint.topic] = endpoint.stats
            elif isinstance(endpoint, Service):
                found[endpoint.name] = endpoint.stats
        return found

    def call_in_executor(self, work: Callable[[], Any], timeout: float) -> Any:
        """Run ``work`` in this node's executor, between its callbacks, and return its result: what
        a request from the command line must do to keep the node's callbacks one at a time."""
        future: Future[Any] = Future()

        def fire() -> None:
            try:
                future.set_result(work())
            except BaseException as exc:
                future.set_exception(exc)
                raise  # the node meets the failure as it would meet a real request's
        self.executor.add_timer(time.monotonic(), fire)
        try:
            return future.result(timeout)
        except FutureTimeout:
            raise NodeError(f"node {self.name!r} did not run the request within {timeout:g} s: it is busy, or it "
                            "does not spin (a node that serves must spin or call spin_once)") from None

    def report_times(self) -> None:
        """Log, per subscription and service, how many messages the node handled and how long each
        took: at INFO with ``hetros launch --node-times`` (``HETROS_NODE_TIMES=1``), else at DEBUG."""
        level = logging.INFO if os.environ.get(NODE_TIMES_VARIABLE, "") not in ("", "0") else logging.DEBUG
        if not self.log.isEnabledFor(level):
            return
        for endpoint in self._closables:
            if isinstance(endpoint, Subscription | Service) and endpoint.stats.count:
                count, mean, std = endpoint.stats.summary()
                name = endpoint.topic if isinstance(endpoint, Subscription) else endpoint.name
                self.log.log(level, "node time on %s: %.3f ± %.3f ms per message over %d", name, mean, std, count)

    def close(self) -> None:
        self.graph.node_closed(self)
        for endpoint in reversed(self._closables):
            endpoint.close()
        self._closables.clear()
        self.executor.wake()
