"""rclpy.node.Node on a hetros node: the endpoints the plan wired, rclpy's calling conventions.

Each ``Node`` an rclpy ``main()`` creates is a view of the hetros node the project runs it as
(bound to the thread): its endpoints must be the ones the project declares for that node,
and hetros's executor runs its callbacks. Names resolve as rclpy resolves them (``'topic'``
-> ``/topic`` under the node's namespace, ``'~/x'`` -> ``/<namespace>/<node>/x``).
"""

from __future__ import annotations

import inspect
import threading
import time
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

from ..._errors import NodeError, ParameterError
from ...plan import ChannelPlan, join_namespace
from ...runtime import Clock, ProjectParameters, Ticker, bound_node, check_hz, listed, type_change_problem
from ...runtime import Node as HetrosNode
from .._flavour import copied, keepable, received
from .._where import caller_place
from .callback_groups import BUILT_IN_GROUPS, CallbackGroup, MutuallyExclusiveCallbackGroup
from .logging import RcutilsLogger
from .parameter import Parameter
from .qos import QoSProfile, ReliabilityPolicy, delivery_conflicts, to_hetros
from .task import Future, Task


def run_callback(hetros: HetrosNode, callback: Callable[..., Any]) -> Callable[..., Any]:
    """``callback`` as the node's executor calls it; one that is a coroutine (``async def``) becomes a task
    stepped by the executor (rclpy runs coroutine callbacks so)."""

    def schedule(step: Callable[[], None]) -> None:
        hetros.executor.add_timer(time.monotonic(), lambda: step())

    def run(*args: Any) -> Any:
        result = callback(*args)
        if result is not None and inspect.iscoroutine(result):
            task = Task(result, schedule)
            task.step()
            return task
        return result
    # a plain function or method cannot start a coroutine of its own: called as it is, one frame fewer
    return callback if inspect.isroutine(callback) and not inspect.iscoroutinefunction(callback) else run


Ready = tuple[Callable[[], Any], CallbackGroup, "Node"]


class _Capture(threading.local):
    """What a custom executor's wait_for_ready_callbacks() receives instead of the callback running (per
    thread); a class default, since asking a thread-local for a missing attribute costs a raised error."""

    ready: list[Ready] | None = None


_capture = _Capture()


def capturing(into: list[Ready] | None) -> None:
    """Make this thread's callbacks land in ``into`` as (handler, group, node) instead of running (None: run)."""
    _capture.ready = into


def guarded(node: Node, hetros: HetrosNode, callback: Callable[..., Any], group: CallbackGroup | None,
            entity: list[Any], again: bool, show: Callable[[Any], None] | None = None) -> Callable[..., Any]:
    """``callback`` run as rclpy's executors run it: its group asked first and told after. A refused call is
    offered again in 10 ms when ``again`` (a message), else dropped (a timer's tick). rclpy's own groups
    matter only where callbacks run in threads of their own (a custom executor's): elsewhere hetros's
    executor runs one callback at a time, and they are not asked. ``show`` prepares a message for the
    callback (rclpy's flavour, :mod:`.._flavour`). This runs before every callback: one flat call."""
    run = run_callback(hetros, callback)
    chosen = group if group is not None else node.default_callback_group
    custom = type(chosen) not in BUILT_IN_GROUPS
    if show is not None:
        inner = run

        def run(message: Any) -> Any:
            show(message)
            return inner(message)

    def attempt(*args: Any) -> Any:
        subject = entity[0] if entity else None
        if not chosen.can_execute(subject) or not chosen.beginning_execution(subject):
            if again:
                hetros.executor.add_timer(time.monotonic() + 0.01, lambda: attempt(*args))
            return None
        try:
            return run(*args)
        finally:
            chosen.ending_execution(subject)

    def call(*args: Any) -> Any:
        ready = _capture.ready
        if ready is not None:
            ready.append((lambda: attempt(*args), chosen, node))
            return None
        return attempt(*args) if custom else run(*args)
    return call


class Publisher:
    """Publishes as rclpy does: the message stays the caller's (``publish(keep=True)``)."""

    def __init__(self, node: Node, inner: Any, msg_type: type[Any], topic: str) -> None:
        self._node = node
        self._inner = inner
        self.msg_type = msg_type
        self.topic_name = topic
        self._where = f"topic {topic}"  # for a wrong type's error, made once: publish is the hot path
        self._class: type[Any] | None = None  # the class last published, and whether its messages go as they are
        self._keepable: Callable[[Any], bool] = bool
        # best effort chosen in code on a topic the project gives no QoS (its transport then blocks a
        # publisher while a reliable subscriber's FIFO is full): the message is dropped instead, counted
        self.best_effort = False
        self.dropped = 0

    @property
    def topic(self) -> str:
        return self.topic_name

    def publish(self, msg: Any) -> None:
        if self.best_effort and not self._inner.has_room():
            self.dropped += 1  # as a best-effort writer does: never waits for a subscriber
            return
        if type(msg) is not self._class:
            self._class, self._keepable = type(msg), keepable(type(msg))
        if self._keepable(msg):
            self._inner.publish(msg, keep=True)
        else:
            self._inner.publish(copied(msg, self.msg_type, self._where))

    def get_subscription_count(self) -> int:
        matched = self._inner.matched
        return 0 if matched is None else int(matched.current)

    def assert_liveliness(self) -> None:
        self._inner.assert_liveliness()

    def destroy(self) -> None:
        self._inner.close()


class Subscription:
    def __init__(self, inner: Any, msg_type: type[Any], topic: str, callback: Callable[[Any], None]) -> None:
        self._inner = inner
        self.msg_type = msg_type
        self.topic_name = topic
        self.callback = callback

    @property
    def topic(self) -> str:
        return self.topic_name

    def get_publisher_count(self) -> int:
        matched = self._inner.matched
        return 0 if matched is None else int(matched.current)

    def destroy(self) -> None:
        self._inner.close()


class Timer:
    def __init__(self, node: Node, period: float, callback: Callable[[], Any], autostart: bool,
                 group: CallbackGroup | None = None) -> None:
        self._node = node
        self._period = period
        self.callback = callback
        self.callback_group = group
        self._inner: Any = None
        self._run = guarded(node, node._hetros, callback, group, [self], again=False)
        if autostart:
            self.reset()

    @property
    def timer_period_ns(self) -> int:
        return int(self._period * 1e9)

    def is_canceled(self) -> bool:
        return self._inner is None or bool(self._inner.cancelled)

    def cancel(self) -> None:
        if self._inner is not None:
            self._inner.cancel()

    def reset(self) -> None:
        self.cancel()
        self._inner = self._node._hetros.create_timer(self._period, self._run)

    def destroy(self) -> None:
        self.cancel()


class Client:
    """A service client as rclpy's: ``call_async`` gives a Future completed while the node spins."""

    def __init__(self, node: Node, inner: Any, srv_type: Any, name: str) -> None:
        self._node = node
        self._inner = inner
        self.srv_type = srv_type
        self.srv_name = name

    def call_async(self, request: Any) -> Future:
        request = copied(request, self.srv_type.Request, f"a request of service {self.srv_name}")
        return Future.wrapping(self._inner.call_async(request), received, self._node._schedule)

    def call(self, request: Any, timeout_sec: float | None = None) -> Any:
        request = copied(request, self.srv_type.Request, f"a request of service {self.srv_name}")
        return received(self._inner.call(request, timeout=3600.0 if timeout_sec is None else timeout_sec))

    def wait_for_service(self, timeout_sec: float | None = None) -> bool:
        """True: the plan wires every client to its server before the graph starts, and a request waits in
        the server's FIFO until the server takes it."""
        return True

    def service_is_ready(self) -> bool:
        return True

    def remove_pending_request(self, future: Future) -> None:
        future.cancel()

    def configure_introspection(self, clock: Any, service_event_qos_profile: Any, introspection_state: Any) -> None:
        from .service_introspection import configure

        configure(self._inner, self.srv_name, introspection_state)

    def destroy(self) -> None:
        self._inner.close()


class Service:
    def __init__(self, inner: Any, srv_type: Any, name: str) -> None:
        self._inner = inner
        self.srv_type = srv_type
        self.srv_name = name

    def configure_introspection(self, clock: Any, service_event_qos_profile: Any, introspection_state: Any) -> None:
        from .service_introspection import configure

        configure(self._inner, self.srv_name, introspection_state)

    def destroy(self) -> None:
        self._inner.close()


class Rate:
    """``node.create_rate(hz)``: ``sleep()`` until the next period of the graph's clock."""

    def __init__(self, node: Node, frequency: float) -> None:
        self._node = node._hetros
        self._stop = node._hetros.graph.stop
        self._ticker = Ticker(node.get_clock(), int(1e9 / check_hz(frequency, "create_rate's frequency")))

    def sleep(self) -> None:
        if not self._ticker.sleep(self._stop):
            from .executors import ExternalShutdownException

            raise ExternalShutdownException("the graph is shutting down")
        self._node.period_began()

    def destroy(self) -> None:
        pass


class SetParametersResult:
    def __init__(self, successful: bool, reason: str = "") -> None:
        self.successful = successful
        self.reason = reason


_Owned = TypeVar("_Owned", "Publisher", "Subscription", "Timer", "Service")


class Node:
    """rclpy's Node, as a view of the hetros node this ``main()`` runs as."""

    PARAM_REL_TOL = 1e-6

    @classmethod
    def run_as_component(cls) -> None:
        """How a node class that a launch file loads as a component (launch_ros's ComposableNode) runs:
        made with no argument, as rclcpp_components makes a C++ one, and spun until shutdown; the
        container's other components are other nodes' threads of the same process."""
        from . import init, spin, try_shutdown

        init()
        make: Callable[[], Node] = cls  # a component's class takes no argument
        node = make()
        try:
            spin(node)
        finally:
            node.destroy_node()
            try_shutdown()

    def __init__(self, node_name: str, *, context: Any = None, cli_args: list[str] | None = None,
                 namespace: str | None = None, use_global_arguments: bool = True, enable_rosout: bool = True,
                 start_parameter_services: bool = True, parameter_overrides: list[Parameter] | None = None,
                 allow_undeclared_parameters: bool = False,
                 automatically_declare_parameters_from_overrides: bool = False,
                 enable_logger_service: bool = False, **_ignored: Any) -> None:
        self._hetros: HetrosNode = bound_node()
        # the project's name and namespace stand over the code's, as a launch file's do in ROS 2
        self._name = self._hetros.ros_name or node_name
        self._namespace = join_namespace(self._hetros.namespace, namespace or "") or "/"
        self._logger = RcutilsLogger(self.get_fully_qualified_name().lstrip("/").replace("/", "."))
        self._overrides: dict[str, Any] = dict(self._hetros.parameters)
        for parameter in parameter_overrides or []:
            self._overrides[parameter.name] = parameter.value
        self._declared: dict[str, Parameter] = {}
        self._allow_undeclared = allow_undeclared_parameters
        self._on_set: list[Callable[[list[Parameter]], Any]] = []
        self._pre_set: list[Callable[[list[Parameter]], list[Parameter]]] = []
        self._post_set: list[Callable[[list[Parameter]], Any]] = []
        # the parameters declared dynamically typed (set while undeclared ones are allowed)
        self._dynamic: set[str] = set()
        # the node's parameter services (`ros2 param`, parameter clients) go through rclpy's rules and callbacks
        # the first rclpy node of the project's node answers its parameter services; each one is also
        # found by its own full name (a main that makes a service node and a client node has both)
        if isinstance(self._hetros.parameter_access, ProjectParameters):
            self._hetros.parameter_access = self
        self._hetros.add_ros_node(self.get_fully_qualified_name(), self)
        self.default_callback_group: CallbackGroup = MutuallyExclusiveCallbackGroup()
        self._owned: list[Publisher | Subscription | Timer | Service] = []  # closed by destroy_node
        self.executor: Any = None
        # every ROS 2 node has use_sim_time, declared: the project's use_sim_time unless the node's parameters
        # say otherwise
        plan = self._hetros.graph.plan
        sim_time = self._overrides.get("use_sim_time", plan.use_sim_time if plan is not None else False)
        self._declared["use_sim_time"] = Parameter("use_sim_time", value=bool(sim_time))
        if automatically_declare_parameters_from_overrides:
            for name, value in self._overrides.items():
                self._declared[name] = Parameter(name, value=value)
        if enable_logger_service:
            self._serve_logger_levels()

    def _serve_logger_levels(self) -> None:
        """``~/get_logger_levels`` and ``~/set_logger_levels``, as rclpy's logger service: levels by
        logger name (``UNSET``, 0, where a logger follows its parent)."""
        from ...interfaces.rcl_interfaces.msg import LoggerLevel, SetLoggerLevelsResult
        from ...interfaces.rcl_interfaces.srv import GetLoggerLevels, SetLoggerLevels
        from .logging import get_logger_level, set_logger_level

        def get_levels(request: Any, response: Any) -> Any:
            response.levels = [LoggerLevel(name=name, level=int(get_logger_level(name))) for name in request.names]
            return response

        def set_levels(request: Any, response: Any) -> Any:
            for wanted in request.levels:
                try:
                    set_logger_level(wanted.name, wanted.level)
                    response.results.append(SetLoggerLevelsResult(successful=True))
                except ValueError as refused:
                    response.results.append(SetLoggerLevelsResult(successful=False, reason=str(refused)))
            return response
        self.create_service(GetLoggerLevels, "~/get_logger_levels", get_levels)
        self.create_service(SetLoggerLevels, "~/set_logger_levels", set_levels)

    # -- names ---------------------------------------------------------------------------------

    def get_name(self) -> str:
        return self._name

    def get_namespace(self) -> str:
        return self._namespace

    def get_fully_qualified_name(self) -> str:
        return f"{self._namespace.rstrip('/')}/{self._name}"

    def resolve_topic_name(self, topic: str, *, only_expand: bool = False) -> str:
        return self._hetros.resolve_name(topic, self._namespace.rstrip("/"), self._name)

    resolve_service_name = resolve_topic_name

    def _schedule(self, work: Callable[[], None]) -> None:
        """Run ``work`` in the node's thread, between callbacks (where rclpy runs a future's callbacks)."""
        self._hetros.executor.add_timer(time.monotonic(), work)

    def get_logger(self) -> RcutilsLogger:
        return self._logger

    def get_clock(self) -> Clock:
        return self._hetros.get_clock()

    # -- endpoints -----------------------------------------------------------------------------

    def create_publisher(self, msg_type: type[Any], topic: str, qos_profile: QoSProfile | int, *,
                         callback_group: CallbackGroup | None = None, event_callbacks: Any = None,
                         qos_overriding_options: Any = None, publisher_class: Any = None) -> Publisher:
        name = self.resolve_topic_name(topic)
        from .event_handler import incompatible_qos_handler, supported

        deadline = matched = lost = None
        if event_callbacks is not None:
            supported(event_callbacks, f"publisher of {name}")
            deadline, matched, lost = event_callbacks.deadline, event_callbacks.matched, event_callbacks.liveliness
        _refuse_overrides(qos_overriding_options, publisher_class, f"publisher of {name}", qos_profile)
        channel = self._checked_channel(name, qos_profile, "publisher")
        inner = self._hetros.create_publisher(
            msg_type, name, qos=to_hetros(qos_profile), on_deadline_missed=deadline, on_matched=matched,
            on_liveliness_lost=lost,
            on_incompatible_qos=incompatible_qos_handler(event_callbacks, self._logger, name, publisher=True))
        publisher = Publisher(self, inner, msg_type, name)
        publisher.best_effort = isinstance(qos_profile, QoSProfile) and "reliability" in qos_profile.chosen and \
            qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT and channel is not None and \
            not channel.qos_given and channel.qos.blocks_publisher
        return self._own(publisher)

    def create_subscription(self, msg_type: type[Any], topic: str, callback: Callable[[Any], None],
                            qos_profile: QoSProfile | int, *, callback_group: CallbackGroup | None = None,
                            event_callbacks: Any = None, qos_overriding_options: Any = None, raw: bool = False,
                            content_filter_options: Any = None, subscription_class: Any = None) -> Subscription:
        name = self.resolve_topic_name(topic)
        from .event_handler import incompatible_qos_handler, supported

        deadline = liveliness = lost = matched = None
        if event_callbacks is not None:
            supported(event_callbacks, f"subscription to {name}")
            deadline, liveliness = event_callbacks.deadline, event_callbacks.liveliness
            lost, matched = event_callbacks.message_lost, event_callbacks.matched
        _refuse_overrides(qos_overriding_options, subscription_class, f"subscription to {name}", qos_profile)
        self._checked_channel(name, qos_profile, "subscription")
        if content_filter_options is not None:
            raise NodeError(f"subscription to {name}: content filters are not supported by hetros; filter in the "
                            "callback")
        if raw:  # ROS 2 hands the serialized message: CDR with its 4-byte encapsulation header
            callback = _serialized(msg_type, callback)
        entity: list[Any] = []
        # a topic's message reaches the callback as hetros delivered it: numeric sequences stay numpy arrays
        # (zero-copy, read-only; they index, iterate and tolist() as array.array does). Showing them in
        # rclpy's flavour costs a view per field per message, 1.25x the one-way latency of small messages
        # (docs/PERFORMANCE.md); services and actions, off the hot path, show it.
        run = guarded(self, self._hetros, callback, callback_group, entity, again=True)
        inner = self._hetros.create_subscription(msg_type, name, run, qos=to_hetros(qos_profile),
                                                 on_deadline_missed=deadline, on_liveliness_changed=liveliness,
                                                 on_message_lost=lost, on_matched=matched,
                                                 on_incompatible_qos=incompatible_qos_handler(
                                                     event_callbacks, self._logger, name, publisher=False))
        subscription = Subscription(inner, msg_type, name, callback)
        entity.append(subscription)
        return self._own(subscription)

    def _checked_channel(self, topic: str, profile: QoSProfile | int, role: str) -> ChannelPlan | None:
        """The plan's channel of ``topic`` (None without a plan), once the code's QoS is checked against it:
        where the project file gives the topic a QoS, a delivery policy the code chose that it contradicts
        (reliability, durability, history) is refused, naming both: the topic's QoS applies to every
        endpoint, and the code would otherwise get what it did not ask for."""
        plan = self._hetros.graph.plan
        channel = plan.channels.get(topic) if plan is not None else None
        conflicts = [] if channel is None or not channel.qos_given else \
            delivery_conflicts(profile, channel.qos, subscription=role == "subscription")
        if not conflicts:
            return channel
        raise NodeError(f"{caller_place()}: the {role} of {topic} asks {'; '.join(conflicts)}: the project file's "
                        f"topics.{topic} is every endpoint's QoS; make the two agree")

    def create_timer(self, timer_period_sec: float, callback: Callable[[], Any],
                     callback_group: CallbackGroup | None = None, clock: Any = None, autostart: bool = True) -> Timer:
        return self._own(Timer(self, float(timer_period_sec), callback, autostart, callback_group))

    def create_rate(self, frequency: float, clock: Any = None) -> Rate:
        return Rate(self, frequency)

    def create_service(self, srv_type: Any, srv_name: str, callback: Callable[[Any, Any], Any], *,
                       qos_profile: Any = None, callback_group: CallbackGroup | None = None) -> Service:
        name = self.resolve_service_name(srv_name)

        def handle(request: Any) -> Any:  # rclpy hands the callback a response to fill
            return copied(callback(received(request), srv_type.Response()), srv_type.Response,
                          f"the response of service {name}")
        return self._own(Service(self._hetros.create_service(srv_type, name, handle), srv_type, name))

    def create_client(self, srv_type: Any, srv_name: str, *, qos_profile: Any = None,
                      callback_group: CallbackGroup | None = None) -> Client:
        name = self.resolve_service_name(srv_name)
        existing = self._hetros.clients.get(name)
        inner = existing if existing is not None else self._hetros.create_client(srv_type, name)
        return Client(self, inner, srv_type, name)

    def create_guard_condition(self, callback: Callable[[], Any], callback_group: CallbackGroup | None = None) -> Any:
        from .executors import GuardCondition

        return GuardCondition(self, callback)

    def count_publishers(self, topic: str) -> int:
        return self._count(topic, "publishers")

    def count_subscribers(self, topic: str) -> int:
        return self._count(topic, "subscribers")

    def _count(self, topic: str, role: str) -> int:
        plan = self._hetros.graph.plan
        channel = None if plan is None else plan.channels.get(self.resolve_topic_name(topic))
        return 0 if channel is None else len(getattr(channel, role))

    def get_topic_names_and_types(self, no_demangle: bool = False) -> list[tuple[str, list[str]]]:
        plan = self._hetros.graph.plan
        if plan is None:
            return []
        return sorted((c.name, [c.type]) for c in plan.channels.values() if c.kind == "topic")

    def get_node_names(self) -> list[str]:
        return [name for name, _ in self.get_node_names_and_namespaces()]

    def get_node_names_and_namespaces(self) -> list[tuple[str, str]]:
        """Every node of the graph (the plan's, by its ROS name), as rclpy's graph query gives them."""
        plan = self._hetros.graph.plan
        if plan is None:
            return [(self._name, self._namespace)]
        found = set()
        for key in plan.nodes:
            if plan.nodes[key].run.startswith("hetros."):
                continue  # the bridges, gateways and clock followers hetros adds are no ROS nodes
            namespace, _, name = plan.full_name(key).rpartition("/")
            found.add((name, namespace or "/"))
        return sorted(found)

    def get_service_names_and_types(self) -> list[tuple[str, list[str]]]:
        plan = self._hetros.graph.plan
        if plan is None:
            return []
        services = {s: t for spec in plan.nodes.values() for s, t in spec.services.items() if "/_action/" not in s}
        services.update({s: t for s, (_, t) in plan.parameter_servers().items()})
        return sorted((name, [typename]) for name, typename in services.items())

    def get_publishers_info_by_topic(self, topic_name: str, no_mangle: bool = False) -> list[Any]:
        return self._endpoint_infos(topic_name, "publishers")

    def get_subscriptions_info_by_topic(self, topic_name: str, no_mangle: bool = False) -> list[Any]:
        return self._endpoint_infos(topic_name, "subscribers")

    def _endpoint_infos(self, topic: str, role: str) -> list[Any]:
        """rclpy's TopicEndpointInfo of each planned endpoint of ``topic`` (node, namespace, type, kind, QoS)."""
        from .topic_endpoint_info import TopicEndpointInfo, TopicEndpointTypeEnum

        plan = self._hetros.graph.plan
        channel = None if plan is None else plan.channels.get(self.resolve_topic_name(topic))
        if plan is None or channel is None:
            return []
        kind = TopicEndpointTypeEnum.PUBLISHER if role == "publishers" else TopicEndpointTypeEnum.SUBSCRIPTION
        infos = []
        for key in getattr(channel, role):
            namespace, _, name = plan.full_name(key).rpartition("/")
            infos.append(TopicEndpointInfo(node_name=name, node_namespace=namespace or "/", topic_type=channel.type,
                                           endpoint_type=kind, qos=channel.qos))
        return infos

    # -- parameters ----------------------------------------------------------------------------

    def declare_parameter(self, name: str, value: Any = None, descriptor: Any = None,
                          ignore_override: bool = False) -> Parameter:
        if isinstance(value, Parameter.Type):
            value = None  # declared by type only: its value comes from the overrides
        chosen = value if ignore_override or name not in self._overrides else self._overrides[name]
        parameter = Parameter(name, value=chosen)
        # declaring sets: rclpy runs the pre-, on- and post-set callbacks registered so far
        result = self._set_atomically(self._pre_setting([parameter]))
        if not result.successful:
            from .exceptions import InvalidParameterValueException

            raise InvalidParameterValueException(name, chosen, result.reason)
        return self._declared.get(name, parameter)

    def declare_parameters(self, namespace: str, parameters: Iterable[tuple[Any, ...]],
                           ignore_override: bool = False) -> list[Parameter]:
        prefix = f"{namespace}." if namespace else ""
        return [self.declare_parameter(prefix + entry[0], entry[1] if len(entry) > 1 else None,
                                       ignore_override=ignore_override) for entry in parameters]

    def has_parameter(self, name: str) -> bool:
        return name in self._declared

    def get_parameter(self, name: str) -> Parameter:
        if name in self._declared:
            live = self._hetros.parameters.get(name, self._declared[name].value)
            return Parameter(name, value=live)
        if self._allow_undeclared:
            return Parameter(name, value=self._overrides.get(name))
        from .exceptions import ParameterNotDeclaredException

        raise ParameterNotDeclaredException(name)

    def get_parameter_or(self, name: str, alternative_value: Parameter | None = None) -> Parameter:
        if name in self._declared:
            return self.get_parameter(name)
        return alternative_value if alternative_value is not None else Parameter(name)

    def get_parameters(self, names: Iterable[str]) -> list[Parameter]:
        return [self.get_parameter(name) for name in names]

    def get_parameter_type(self, name: str) -> int:
        return int(self.get_parameter(name).type_)

    def get_parameter_types(self, names: Iterable[str]) -> list[int]:
        return [self.get_parameter_type(name) for name in names]

    def describe_parameter(self, name: str) -> Any:
        from ...interfaces.rcl_interfaces.msg import ParameterDescriptor

        return ParameterDescriptor(name=name, type=self.get_parameter_type(name),
                                   dynamic_typing=name in self._dynamic)

    def describe_parameters(self, names: Iterable[str]) -> list[Any]:
        return [self.describe_parameter(name) for name in names]

    def list_parameters(self, prefixes: list[str], depth: int) -> Any:
        from ...interfaces.rcl_interfaces.msg import ListParametersResult

        if depth < 0:
            raise ValueError("The depth must be greater than or equal to zero")
        names, found_prefixes = listed(list(self._declared), list(prefixes), depth)
        return ListParametersResult(names=names, prefixes=found_prefixes)

    def set_parameters(self, parameters: list[Parameter]) -> list[SetParametersResult]:
        """rclpy's order: the pre-set callbacks may change the list; then each parameter on its own is
        validated (on-set), stored, and announced (post-set)."""
        parameters = self._pre_setting(parameters)
        self._check_declared(parameters)
        return [self._set_atomically([parameter]) for parameter in parameters]

    def set_parameters_atomically(self, parameters: list[Parameter]) -> SetParametersResult:
        parameters = self._pre_setting(parameters)
        self._check_declared(parameters)
        return self._set_atomically(parameters)

    def _check_declared(self, parameters: list[Parameter]) -> None:
        undeclared = [p.name for p in parameters if p.name not in self._declared]
        if undeclared and not self._allow_undeclared:
            from .exceptions import ParameterNotDeclaredException

            raise ParameterNotDeclaredException(undeclared)

    def _pre_setting(self, parameters: list[Parameter]) -> list[Parameter]:
        for callback in self._pre_set:
            parameters = list(callback(list(parameters)))
            if not parameters:
                raise ParameterError(f"node {self._name!r}: a pre-set parameters callback left no parameter to "
                                     "set (rclpy refuses an empty list too)")
        return parameters

    def _set_atomically(self, parameters: list[Parameter]) -> SetParametersResult:
        """rclpy's common path: a parameter keeps its type unless declared dynamically typed (one set
        while undeclared ones are allowed is); the on-set callbacks may refuse; a parameter set to
        NOT_SET is undeclared."""
        for parameter in parameters:
            old = self._declared.get(parameter.name)
            if old is not None and parameter.name not in self._dynamic and \
                    (problem := type_change_problem(self._name, parameter.name, old.value, parameter.value)):
                return SetParametersResult(False, problem)
        for callback in self._on_set:
            verdict = callback(parameters)
            if verdict is not None and not getattr(verdict, "successful", True):
                return SetParametersResult(False, getattr(verdict, "reason", ""))
        for parameter in parameters:
            if parameter.type_ == Parameter.Type.NOT_SET and parameter.name in self._declared:
                del self._declared[parameter.name]
                self._dynamic.discard(parameter.name)
                if parameter.name in self._hetros.parameters:
                    self._hetros.delete_parameter(parameter.name)
                continue
            if parameter.name not in self._declared and self._allow_undeclared:
                self._dynamic.add(parameter.name)
            self._declared[parameter.name] = parameter
            if parameter.value is not None:
                self._hetros.store_parameter(parameter.name, parameter.value)
        for post in self._post_set:
            post(parameters)
        return SetParametersResult(True)

    # what the node's parameter services (``ros2 param``, ``hetros param``, parameter clients) read and set

    def parameter_names(self) -> list[str]:
        return list(self._declared)

    def parameter_value(self, name: str) -> Any:
        return self.get_parameter(name).value

    def set_parameters_as_one(self, changes: list[tuple[str, Any]]) -> tuple[bool, str]:
        from .exceptions import ParameterNotDeclaredException

        try:
            result = self.set_parameters_atomically([Parameter(name, value=value) for name, value in changes])
        except ParameterNotDeclaredException as refused:
            return False, str(refused)
        return result.successful, result.reason

    def add_on_set_parameters_callback(self, callback: Callable[[list[Parameter]], Any]) -> None:
        self._on_set.append(callback)

    def remove_on_set_parameters_callback(self, callback: Callable[[list[Parameter]], Any]) -> None:
        self._on_set.remove(callback)

    def add_pre_set_parameters_callback(self, callback: Callable[[list[Parameter]], list[Parameter]]) -> None:
        self._pre_set.append(callback)

    def remove_pre_set_parameters_callback(self, callback: Callable[[list[Parameter]], list[Parameter]]) -> None:
        self._pre_set.remove(callback)

    def add_post_set_parameters_callback(self, callback: Callable[[list[Parameter]], Any]) -> None:
        self._post_set.append(callback)

    def remove_post_set_parameters_callback(self, callback: Callable[[list[Parameter]], Any]) -> None:
        self._post_set.remove(callback)

    def undeclare_parameter(self, name: str) -> None:
        self._declared.pop(name, None)
        self._dynamic.discard(name)

    # -- the end ---------------------------------------------------------------------------------

    def _own(self, entity: _Owned) -> _Owned:
        self._owned.append(entity)
        return entity

    def destroy_node(self) -> None:
        """Close what this node created, as rclpy does: its publishers (a subscription of the process hears
        them go: liveliness, matched), subscriptions, timers and services. Clients stay: the node's clients
        of one service are one hetros client, shared by every rclpy node of the process."""
        owned, self._owned = self._owned, []
        for entity in reversed(owned):
            entity.destroy()
        self._hetros.remove_ros_node(self.get_fully_qualified_name())
        if self._hetros.parameter_access is self:
            self._hetros.parameter_access = ProjectParameters(self._hetros)

    def destroy_publisher(self, publisher: Publisher) -> bool:
        publisher.destroy()
        return True

    def destroy_subscription(self, subscription: Subscription) -> bool:
        subscription.destroy()
        return True

    def destroy_timer(self, timer: Timer) -> bool:
        timer.destroy()
        return True

    def destroy_client(self, client: Client) -> bool:
        return True

    def destroy_service(self, service: Service) -> bool:
        service.destroy()
        return True

    def destroy_rate(self, rate: Rate) -> bool:
        return True


def _refuse_overrides(options: Any, cls: Any, where: str, qos: QoSProfile | int) -> None:
    """``qos_overriding_options`` keeps the QoS given (as ROS 2 does without override parameters): the
    project file's ``topics:`` is where hetros overrides a topic's QoS, for every endpoint at once. Its
    callback still validates the QoS, as rclpy's does."""
    if options is not None:
        from .qos_overriding_options import validate

        validate(options, qos if isinstance(qos, QoSProfile) else QoSProfile(depth=qos), where)
    if cls is not None:
        raise NodeError(f"{where}: a custom publisher or subscription class is not supported by hetros; remove it")


def _serialized(msg_type: type[Any], callback: Callable[[Any], None]) -> Callable[[Any], None]:
    """The callback of a ``raw=True`` subscription: each message as ROS 2 serializes it (bytes)."""
    from ...msg import registry

    codec = registry().codec(getattr(msg_type, "__msgtype__", ""))

    def raw(message: Any) -> None:
        size = codec.size(message)
        data = bytearray(4 + size)
        data[1] = 1  # CDR little endian
        codec.encode(message, memoryview(data)[4:])
        callback(bytes(data))

    return raw
