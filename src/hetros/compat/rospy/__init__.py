"""rospy, as hetros serves it to the nodes it runs (``hetros.compat``): ``init_node``, ``Publisher``,
``Subscriber``, ``Rate``, ``spin``, services and parameters with rospy's names and calling conventions,
on the hetros node the project wires. Outside hetros's processes ``import rospy`` is ROS 1's own.

As in rospy, callbacks run beside the node's main thread: the first subscriber or service starts a
thread that runs the node's callbacks, so a ``while not rospy.is_shutdown()`` loop and callbacks go on
together. Names resolve as rospy's: ``'chatter'`` is ``/chatter``, ``'~x'`` is ``/<node>/x``.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time as _time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from ..._errors import Error, ParameterError, ShutdownError
from ...msg import Message, registry
from ...msg import copy as copy_message
from ...runtime import ROSPY_CONSOLE, Ticker, check_hz, node_logger, yield_to_callbacks
from ...runtime import Node as HetrosNode
from ...runtime import bound_node as _bound_node
from ...runtime import ros_main as _ros_main
from .._flavour import keepable

__all__ = [
    "Duration",
    "Publisher",
    "ROSException",
    "ROSInterruptException",
    "Rate",
    "Service",
    "ServiceException",
    "ServiceProxy",
    "Subscriber",
    "Time",
    "Timer",
    "TimerEvent",
    "delete_param",
    "get_caller_id",
    "get_name",
    "get_param",
    "get_param_names",
    "get_rostime",
    "get_time",
    "has_param",
    "init_node",
    "is_shutdown",
    "logdebug",
    "logerr",
    "logfatal",
    "loginfo",
    "logwarn",
    "myargv",
    "on_shutdown",
    "resolve_name",
    "search_param",
    "set_param",
    "signal_shutdown",
    "sleep",
    "spin",
    "wait_for_message",
    "wait_for_service",
]


class ROSException(Error):
    """rospy's base exception."""


class ROSInterruptException(ROSException, ShutdownError):
    """The node is shutting down: raised from ``Rate.sleep`` and ``rospy.sleep``, as rospy does."""


class ServiceException(ROSException):
    """A service call that failed."""


# how long a stopping node's callbacks go on with the messages already delivered to it (Executor.drain)
DRAIN_SECONDS = 0.5


class _State:
    """The rospy state of one hetros node (its thread): name, callback thread, shutdown hooks."""

    def __init__(self, hetros: HetrosNode) -> None:
        self.hetros = hetros
        self.name = hetros.name
        self.spinner: threading.Thread | None = None
        self.shutdown_reason = ""
        self.lock = threading.Lock()
        # what a callback raised in the callbacks' thread: the node's main thread raises it (the node fails,
        # the launcher reports it) at its next rospy call
        self.failure: BaseException | None = None

    def start_callbacks(self) -> None:
        """rospy runs callbacks in threads of their own: one thread here runs the node's, beside its main."""
        with self.lock:
            if self.spinner is not None:
                return
            hetros = self.hetros
            hetros.spun = True

            # the node's main thread runs beside its callbacks (and waits for what they hand it): a hot
            # spin here hands the GIL over at every poll, as when another thread of the process feeds it
            hetros.executor.yield_every = 1

            def run() -> None:
                with _ros_main(hetros):  # callbacks call rospy too: this thread runs as the node
                    try:
                        while not hetros.graph.stop.is_set() and not self.shutdown_reason and self.failure is None:
                            hetros.executor.spin_once(0.1)
                        if hetros.graph.stop.is_set() and self.failure is None:
                            with contextlib.suppress(ShutdownError):  # a callback blocked by the stop ends it
                                hetros.executor.drain(DRAIN_SECONDS)
                    except BaseException as exc:
                        self.failure = exc
            self.spinner = threading.Thread(target=run, name=f"rospy callbacks:{hetros.name}", daemon=True)
            self.spinner.start()
            yield_to_callbacks()


_states: dict[int, _State] = {}
_states_lock = threading.Lock()


def _state() -> _State:
    hetros = _bound_node()
    with _states_lock:
        state = _states.get(id(hetros))
        if state is None or state.hetros is not hetros:
            state = _states[id(hetros)] = _State(hetros)
        return state


def _resolve(name: str) -> str:
    """rospy's resolution (``~x`` is private, as ``~/x``) under the namespace and remaps the project gives."""
    state = _state()
    private = "~/" + name[1:].lstrip("/") if name.startswith("~") else name
    return state.hetros.resolve_name(private, node_name=state.name)


# header.seq of the headers rospy code holds now: received ones while their callback runs, published ones
# after publish (rospy writes the publisher's count into the message it sends); bounded, keyed by id
_SEQS: dict[int, int] = {}
_SEQS_KEPT = 1024


def _seq_of(header: Any) -> int:
    return _SEQS.get(id(header), 0)


def _set_seq(header: Any, value: int) -> None:
    if len(_SEQS) >= _SEQS_KEPT:
        del _SEQS[next(iter(_SEQS))]
    _SEQS[id(header)] = int(value)


def _secs(stamp: Any) -> int:
    return int(stamp.sec)


def _nsecs(stamp: Any) -> int:
    return int(stamp.nanosec)


def _to_sec(stamp: Any) -> float:
    return float(stamp.sec) + float(stamp.nanosec) / 1e9


def _to_nsec(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _is_zero(stamp: Any) -> bool:
    return _to_nsec(stamp) == 0


def _before(stamp: Any, other: Any) -> bool:
    return _to_nsec(stamp) < _to_nsec(other)


def _not_after(stamp: Any, other: Any) -> bool:
    return _to_nsec(stamp) <= _to_nsec(other)


def _after(stamp: Any, other: Any) -> bool:
    return _to_nsec(stamp) > _to_nsec(other)


def _not_before(stamp: Any, other: Any) -> bool:
    return _to_nsec(stamp) >= _to_nsec(other)


def _ros1_layouts() -> None:
    """ROS 1's view of the messages ROS 2 changed, for rospy code: ``header.seq`` (hetros transports carry
    ROS 2's Header, so a subscriber's seq is the count of what its subscription received, 1 first — rospy's
    publisher count wherever one publisher's stream arrives whole, as hetros's reliable topics do), and
    ``stamp.secs``, ``nsecs``, ``to_sec()``, ``to_nsec()`` on times and durations. The classes gain
    properties and methods only: their slots and codecs stay as they are."""
    header = registry().get("std_msgs/msg/Header")
    if not isinstance(header.__dict__.get("seq"), property):
        header.seq = property(_seq_of, _set_seq)
    for typename in ("builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"):
        stamp = registry().get(typename)
        if not isinstance(stamp.__dict__.get("secs"), property):
            stamp.secs, stamp.nsecs = property(_secs), property(_nsecs)
            stamp.to_sec, stamp.to_nsec, stamp.is_zero = _to_sec, _to_nsec, _is_zero
            stamp.__lt__, stamp.__le__ = _before, _not_after
            stamp.__gt__, stamp.__ge__ = _after, _not_before


_ros1_layouts()


# -- the node -------------------------------------------------------------------------------------


def init_node(name: str, argv: list[str] | None = None, anonymous: bool = False, log_level: int | None = None,
              disable_rostime: bool = False, disable_rosout: bool = False, disable_signals: bool = False,
              xmlrpc_port: int = 0, tcpros_port: int = 0) -> None:
    """Name the node (its logs and ``get_name()``); its endpoints are the ones the project gives its hetros
    node. ``anonymous`` adds rospy's suffix to the name it reports."""
    state = _state()
    if state.hetros.ros_name:  # the project's (a launch file's) name stands over the code's, anonymous or not
        state.name = state.hetros.ros_name
        return
    state.name = f"{name}_{id(state) % 100000}_{int(_time.time() * 1000) % 100000}" if anonymous else name


def get_name() -> str:
    state = _state()
    return f"{state.hetros.namespace}/{state.name}"


get_caller_id = get_name


def myargv(argv: list[str] | None = None) -> list[str]:
    """``argv`` without ROS remapping arguments (``name:=value``)."""
    return [arg for arg in (sys.argv if argv is None else argv) if ":=" not in arg]


def is_shutdown() -> bool:
    state = _state()
    if state.failure is not None:
        raise state.failure
    return state.hetros.graph.stop.is_set() or bool(state.shutdown_reason)


def signal_shutdown(reason: str) -> None:
    _state().shutdown_reason = reason or "signal_shutdown"


def on_shutdown(hook: Callable[[], Any]) -> None:
    _state().hetros.graph.on_shutdown(hook)


def spin() -> None:
    """Keep the node alive until shutdown; its callbacks run meanwhile (in their thread)."""
    state = _state()
    state.start_callbacks()
    # this thread only looks at the stop flag ten times a second now: the callback thread's hot spin need
    # not hand it the GIL at every poll (0.5 µs each)
    state.hetros.executor.alone()
    while not is_shutdown():
        state.hetros.graph.stop.wait(0.1)
    # the node closes once its main returns: first its callbacks handle what was delivered before the stop
    if state.spinner is not None and state.spinner is not threading.current_thread():
        state.spinner.join(DRAIN_SECONDS + 1.0)


# -- time -----------------------------------------------------------------------------------------


def _total(secs: float, nsecs: int) -> tuple[int, int]:
    return divmod(round(secs * 1_000_000_000) + int(nsecs), 1_000_000_000)


class Duration(registry().get("builtin_interfaces/msg/Duration")):  # type: ignore[misc]
    """rospy.Duration: ``secs``, ``nsecs``, ``to_sec()``; a builtin_interfaces/Duration message too, so that
    it goes into messages as it is."""

    __slots__ = ()

    def __init__(self, secs: float = 0, nsecs: int = 0) -> None:
        sec, nanosec = _total(secs, nsecs)
        super().__init__(sec=sec, nanosec=nanosec)

    @classmethod
    def from_sec(cls, seconds: float) -> Duration:
        return cls(seconds)

    def __add__(self, other: Any) -> Duration:
        return Duration(0, self.to_nsec() + other.to_nsec())

    def __sub__(self, other: Any) -> Duration:
        return Duration(0, self.to_nsec() - other.to_nsec())

    def __repr__(self) -> str:
        return f"rospy.Duration[{self.to_nsec()}]"


class Time(registry().get("builtin_interfaces/msg/Time")):  # type: ignore[misc]
    """rospy.Time: the graph's clock (``Time.now()``); a builtin_interfaces/Time message too, so that
    ``header.stamp = rospy.Time.now()`` is a stamp."""

    __slots__ = ()

    def __init__(self, secs: float = 0, nsecs: int = 0) -> None:
        sec, nanosec = _total(secs, nsecs)
        super().__init__(sec=sec, nanosec=nanosec)

    @classmethod
    def now(cls) -> Time:
        return cls(0, _state().hetros.get_clock().now_ns())

    @classmethod
    def from_sec(cls, seconds: float) -> Time:
        return cls(seconds)

    def __add__(self, other: Any) -> Time:
        return Time(0, self.to_nsec() + other.to_nsec())

    def __sub__(self, other: Any) -> Any:
        """Time - Time is a Duration; Time - Duration a Time (as rospy)."""
        if isinstance(other, Duration):
            return Time(0, self.to_nsec() - other.to_nsec())
        return Duration(0, self.to_nsec() - other.to_nsec())

    def __repr__(self) -> str:
        return f"rospy.Time[{self.to_nsec()}]"


def get_rostime() -> Time:
    return Time.now()


def get_time() -> float:
    return float(Time.now().to_sec())


def sleep(duration: float | Duration) -> None:
    """Sleep on the graph's clock; ROSInterruptException when the node shuts down meanwhile."""
    seconds = duration.to_sec() if isinstance(duration, Duration) else float(duration)
    hetros = _state().hetros
    clock = hetros.get_clock()
    if not clock.wait_until(clock.now_ns() + int(seconds * 1e9), hetros.graph.stop) or is_shutdown():
        raise ROSInterruptException("rospy.sleep() interrupted: the node is shutting down")


class Rate:
    """``Rate(hz).sleep()``: the rest of the period, on the graph's clock."""

    def __init__(self, hz: float) -> None:
        self._hetros = _state().hetros
        self._ticker = Ticker(self._hetros.get_clock(), int(1e9 / check_hz(hz, "rospy.Rate's hz")))

    def sleep(self) -> None:
        if not self._ticker.sleep(self._hetros.graph.stop) or is_shutdown():
            raise ROSInterruptException("rospy.Rate.sleep() interrupted: the node is shutting down")
        self._hetros.period_began()

    def remaining(self) -> Duration:
        return Duration(0, max(self._ticker.due - self._ticker.clock.now_ns(), 0))


# -- logging --------------------------------------------------------------------------------------


def _log(level: int, message: Any, *args: Any) -> None:
    text = str(message) % args if args else str(message)
    node_logger(_state().name).log(level, "%s", text, extra=ROSPY_CONSOLE)


def logdebug(message: Any, *args: Any, **_kwargs: Any) -> None:
    _log(10, message, *args)


def loginfo(message: Any, *args: Any, **_kwargs: Any) -> None:
    _log(20, message, *args)


def logwarn(message: Any, *args: Any, **_kwargs: Any) -> None:
    _log(30, message, *args)


def logerr(message: Any, *args: Any, **_kwargs: Any) -> None:
    _log(40, message, *args)


def logfatal(message: Any, *args: Any, **_kwargs: Any) -> None:
    _log(50, message, *args)


# -- topics ---------------------------------------------------------------------------------------


def _given(data_class: type[Any], args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
    """rospy's publish and call conventions: a message, or the fields of one (positional or by name)."""
    if len(args) == 1 and not kwargs and isinstance(args[0], Message):
        return args[0]
    return data_class(*args, **kwargs)


def _message(data_class: type[Any], args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
    """:func:`_given`, copied into hetros's own class (served types are flavoured)."""
    return copy_message(_given(data_class, args, kwargs))


class Publisher:
    def __init__(self, name: str, data_class: type[Any], subscriber_listener: Any = None, tcp_nodelay: bool = False,
                 latch: bool = False, headers: Any = None, queue_size: int | None = None) -> None:
        self.name = _resolve(name)
        self.data_class = data_class
        self.type = getattr(data_class, "__msgtype__", "")
        hetros = _state().hetros
        # a latched topic keeps its last message for late subscribers (transient_local): where the project's
        # QoS does not, the launch says so (queue_size is rospy's send buffer, not the topic's QoS)
        asked = replace(hetros.graph.qos_of(self.name, None), durability="transient_local") if latch else None
        self._inner = hetros.create_publisher(data_class, self.name, qos=asked)
        if headers:
            node_logger(hetros.name).warning(
                "publisher of %s: headers=%r are not sent: hetros has no per-connection headers (carry what "
                "the subscriber needs in the message)", self.name, headers)
        self._seq = 0  # rospy's count of messages published, written into their header.seq
        # the class last published, whether its messages go as they are, and whether they carry a header.seq:
        # asked once per class, not per publish
        self._class: type[Any] | None = None
        self._keepable: Callable[[Any], bool] = bool
        self._headed = False

    def publish(self, *args: Any, **kwargs: Any) -> None:
        message = _given(self.data_class, args, kwargs)
        if type(message) is not self._class:
            self._class, self._keepable = type(message), keepable(type(message))
            self._headed = hasattr(message, "header") and hasattr(type(message.header), "seq")
        if self._keepable(message):
            self._inner.publish(message, keep=True)
        else:
            message = copy_message(message)
            self._inner.publish(message)
        self._seq += 1
        if self._headed:
            _set_seq(message.header, self._seq)

    def get_num_connections(self) -> int:
        plan = _state().hetros.graph.plan
        channel = None if plan is None else plan.channels.get(self.name)
        return 0 if channel is None else len(channel.subscribers)

    def unregister(self) -> None:
        self._inner.close()


class Subscriber:
    def __init__(self, name: str, data_class: type[Any], callback: Callable[..., Any] | None = None,
                 callback_args: Any = None, queue_size: int | None = None, buff_size: int = 65536,
                 tcp_nodelay: bool = False) -> None:
        self.name = _resolve(name)
        self.data_class = data_class
        state = _state()

        received = 0
        header = "header" in getattr(data_class, "__fieldnames__", ())

        def deliver(message: Any) -> None:
            nonlocal received
            received += 1
            if callback is None:
                return
            if header:
                _set_seq(message.header, received)
            try:
                callback(message) if callback_args is None else callback(message, callback_args)
            finally:
                if header:
                    _SEQS.pop(id(message.header), None)
            # a thread the callback woke (a main thread waiting for what it received) runs now, not after the
            # executor's next turn in this thread: 9.1 µs -> 6.2 from the callback to the woken main thread
            os.sched_yield()
        self._inner = state.hetros.create_subscription(data_class, self.name, deliver)
        state.start_callbacks()

    def unregister(self) -> None:
        self._inner.close()


def wait_for_message(topic: str, topic_type: type[Any], timeout: float | None = None) -> Any:
    subscription = _state().hetros.create_subscription(topic_type, _resolve(topic))
    try:
        return subscription.take(timeout)
    except Error as exc:
        raise ROSException(f"wait_for_message({topic}): {exc}") from exc
    finally:
        subscription.close()


# -- services -------------------------------------------------------------------------------------


class Service:
    """Serves a service; the handler returns the response, or its fields (one value, a tuple, a dict)."""

    def __init__(self, name: str, service_class: Any, handler: Callable[[Any], Any], buff_size: int = 65536,
                 error_handler: Any = None) -> None:
        self.resolved_name = _resolve(name)
        response_class = service_class.Response

        def handle(request: Any) -> Any:
            answer = handler(request)
            if isinstance(answer, Message):
                return answer
            if isinstance(answer, dict):
                return response_class(**answer)
            return response_class(*answer) if isinstance(answer, tuple | list) else response_class(answer)
        state = _state()
        self._inner = state.hetros.create_service(service_class, self.resolved_name, handle)
        state.start_callbacks()

    def shutdown(self, reason: str = "") -> None:
        self._inner.close()


class ServiceProxy:
    """``proxy(a, b)`` or ``proxy.call(request)``: the response, or ServiceException."""

    def __init__(self, name: str, service_class: Any, persistent: bool = False, headers: Any = None) -> None:
        self.resolved_name = _resolve(name)
        self._request = service_class.Request
        hetros = _state().hetros
        existing = hetros.clients.get(self.resolved_name)
        self._inner = existing if existing is not None else hetros.create_client(service_class, self.resolved_name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.call(*args, **kwargs)

    def call(self, *args: Any, **kwargs: Any) -> Any:
        try:
            return self._inner.call(_message(self._request, args, kwargs), timeout=3600.0)
        except Error as exc:
            raise ServiceException(f"service [{self.resolved_name}] call failed: {exc}") from exc

    def close(self) -> None:
        pass


def wait_for_service(service: str, timeout: float | None = None) -> None:
    """Returns at once: the plan wires every client to its server before the graph starts, and a request
    waits in the server's FIFO until the server takes it."""


# -- parameters -----------------------------------------------------------------------------------

_MISSING: Any = object()


_globals: dict[str, Any] | None = None  # ROS 1's parameter server as this process sees it (the plan's)


def _server() -> dict[str, Any]:
    """The project's global parameters (``parameters:``, absolute names), one copy per process: what one
    node of the process sets, the others read; other processes keep the project's values."""
    global _globals
    if _globals is None:
        plan = _state().hetros.graph.plan
        with _states_lock:
            if _globals is None:
                _globals = dict(plan.parameters) if plan is not None else {}
    return _globals


def _parameter_key(name: str) -> tuple[bool, str]:
    """(private, key) of a parameter name as rospy resolves it: ``~x`` and ``/<ns>/<node>/x`` are the node's
    own (``x``, the project's ``parameters:`` of the node); any other name is global, by its full name
    (a relative one under the node's namespace)."""
    if name.startswith("~"):
        return True, name[1:].lstrip("/")
    full = name if name.startswith("/") else f"{_state().hetros.namespace.rstrip('/')}/{name}"
    own = f"{get_name()}/"
    if full.startswith(own):
        return True, full[len(own):]
    return False, full


def _parameter_name(name: str) -> str:
    """The node's own parameter a name reaches: private names, and (as hetros projects have always put a
    rospy node's parameters under the node) a global name the server does not hold."""
    private, key = _parameter_key(name)
    return key if private else name.lstrip("~/")


def get_param(name: str, default: Any = _MISSING) -> Any:
    """As rospy: a namespace of parameters (``gains`` over ``gains/P``, ``gains/I``) is a dictionary. A global
    name is looked up on the server, then (for projects that give a rospy node all its parameters under the
    node) among the node's own."""
    hetros = _state().hetros
    private, key = _parameter_key(name)
    if not private:
        server = _server()
        if key in server:
            return server[key]
        below = _namespace_of(server, key)
        if below:
            return below
        key = name.lstrip("/")
    try:
        return hetros.get_parameter(key)
    except ParameterError as exc:
        below = _namespace_of(hetros.parameters, key)
        if below:
            return below
        if default is not _MISSING:
            return default
        raise KeyError(name) from exc


def _namespace_of(parameters: dict[str, Any], key: str) -> dict[str, Any]:
    tree: dict[str, Any] = {}
    prefix = f"{key.rstrip('/')}/"
    for full, value in parameters.items():
        if full.startswith(prefix):
            *parents, leaf = full[len(prefix):].split("/")
            branch = tree
            for parent in parents:
                branch = branch.setdefault(parent, {})
            branch[leaf] = value
    return tree


def has_param(name: str) -> bool:
    return get_param(name, _MISSING_DEFAULT) is not _MISSING_DEFAULT


_MISSING_DEFAULT = object()


def set_param(name: str, value: Any) -> None:
    """A private name sets the node's own parameter; a global one, the server's (a dictionary: each leaf)."""
    private, key = _parameter_key(name)
    if private:
        _state().hetros.set_parameter(key, value)
        return
    server = _server()
    for below in [k for k in server if k.startswith(f"{key}/")]:
        del server[below]
    server.update(_leaves(key, value))


def _leaves(key: str, value: Any) -> dict[str, Any]:
    """A value set under ``key`` as the server's leaves (a dictionary nests its names under ``key``)."""
    if not isinstance(value, dict):
        return {key: value}
    return {leaf: v for name, inner in value.items() for leaf, v in _leaves(f"{key}/{name}", inner).items()}


def delete_param(name: str) -> None:
    """As rospy: KeyError when the parameter does not exist."""
    private, key = _parameter_key(name)
    server = _server()
    if not private and (key in server or _namespace_of(server, key)):
        for found in [k for k in server if k == key or k.startswith(f"{key}/")]:
            del server[found]
        return
    try:
        _state().hetros.delete_parameter(_parameter_name(name))
    except ParameterError as exc:
        raise KeyError(name) from exc


def search_param(name: str) -> str | None:
    """rospy's search: ``name`` in the node's own namespace, then in each namespace above it; its full name,
    or None."""
    if name.startswith(("/", "~")):
        return name if has_param(name) else None
    namespace = get_name().rsplit("/", 1)[0]
    while True:
        candidate = f"{namespace}/{name}"
        if candidate in _server() or _namespace_of(_server(), candidate):
            return candidate
        if not namespace:
            break
        namespace = namespace.rsplit("/", 1)[0]
    return f"{get_name()}/{name}" if has_param(f"~{name}") else None


def get_param_names() -> list[str]:
    """Every parameter's full name: the server's and the node's own."""
    own = [f"{get_name()}/{key}" for key in _state().hetros.parameters]
    return sorted({*_server(), *own})


def resolve_name(name: str, caller_id: str | None = None) -> str:
    """``name`` resolved as rospy resolves it: ``~private`` under the node, relative under its namespace,
    remaps applied."""
    return _resolve(name)


# -- timers ---------------------------------------------------------------------------------------


class TimerEvent:
    """What a rospy.Timer callback gets: when this call and the last one were due and when they ran."""

    def __init__(self, last_expected: Time | None, last_real: Time | None, current_expected: Time,
                 current_real: Time, last_duration: float | None) -> None:
        self.last_expected, self.last_real = last_expected, last_real
        self.current_expected, self.current_real = current_expected, current_real
        self.last_duration = last_duration


class Timer:
    """rospy.Timer: ``callback(event)`` every ``period`` in a thread of its own, on the graph's clock, until
    ``shutdown()`` or the node's end; ``oneshot`` calls it once."""

    def __init__(self, period: Duration, callback: Callable[[TimerEvent], Any], oneshot: bool = False,
                 reset: bool = False) -> None:
        state = _state()
        self._hetros = state.hetros
        self._period_ns = period.secs * 1_000_000_000 + period.nsecs
        if self._period_ns <= 0 and not oneshot:
            raise ROSException(f"rospy.Timer period must be positive, not {period.to_sec()} s")
        self._callback, self._oneshot = callback, oneshot
        self._stopped = threading.Event()
        self._state = state
        self._thread = threading.Thread(target=self._run, name=f"rospy timer:{state.name}", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        with _ros_main(self._hetros):  # the callback calls rospy too: this thread runs as the node
            self._tick()

    def _tick(self) -> None:
        clock = self._hetros.get_clock()
        ticker = Ticker(clock, max(self._period_ns, 1))
        stop = self._hetros.graph.stop
        last_expected: Time | None = None
        last_real: Time | None = None
        last_duration: float | None = None
        while not self._stopped.is_set():
            expected = ticker.due
            if not ticker.sleep(stop) or self._stopped.is_set():
                return
            real = Time(0, clock.now_ns())
            event = TimerEvent(last_expected, last_real, Time(0, expected), real, last_duration)
            started = _time.perf_counter()
            try:
                self._callback(event)
            except BaseException as exc:  # the node fails at its next rospy call, as for a callback
                self._state.failure = exc
                return
            last_expected, last_real, last_duration = Time(0, expected), real, _time.perf_counter() - started
            if self._oneshot:
                return

    def shutdown(self) -> None:
        self._stopped.set()

    def is_alive(self) -> bool:
        return self._thread.is_alive()
