"""The seam between the runtime and the transports: one registered factory per kind of edge.

The plan names the transport of every edge (``inproc``, ``shm``, ``dds``; ``tcpros`` for
every endpoint of a ``kind: ros1`` node). The runtime looks the kind up here and asks the
:class:`Transport` it gets to open writers and readers; it never names a transport. A
transport's module is imported the first time a process needs that kind, so a process whose
edges are all in shared memory never loads DDS or the ROS 1 stack.

Adding a transport is one sub-package that subclasses :class:`Transport` and one line in
``_REGISTRY`` (or a :func:`register` call); ``tests/conformance`` runs its writers and readers.
"""

from __future__ import annotations

import importlib
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .._errors import TransportError
from .._qos import QoS
from ._base import Codec, Reader, WaitSource, Wake, Writer

if TYPE_CHECKING:
    from ..msg import TypeRegistry
    from ..plan import EdgePlan, Plan

# kind -> "module:class"; the module is imported on first use
_REGISTRY: dict[str, str] = {
    "inproc": "hetros.transport._inproc:InprocTransport",
    "shm": "hetros.transport.shm:ShmTransport",
    "dds": "hetros.transport.dds:DdsTransport",
    "tcpros": "hetros.transport.tcpros:Ros1Transport",
}
_loaded: dict[str, type[Transport]] = {}
_registry_lock = threading.Lock()


@dataclass(frozen=True)
class Endpoint:
    """One node's end of one channel, as a transport is asked to open it.

    ``edges`` are the plan's edges of this endpoint that this transport carries (empty for
    a graph without a project, and for ROS 1 nodes, whose peers the ROS 1 master knows).
    """

    name: str
    node: str
    typename: str
    qos: QoS
    envelope: bool = False
    edges: tuple[EdgePlan, ...] = ()


@dataclass
class TransportContext:
    """What every transport of one process' graph shares."""

    plan: Plan | None
    process: str
    session: str
    stop: threading.Event
    types: TypeRegistry
    codec: Callable[[str, bool], Codec]


class Transport(ABC):
    """One kind of edge within one process' graph: opens its writers and readers.

    One instance per kind and process, made on first use; ``close`` ends everything it opened.
    """

    kind = ""

    def __init__(self, context: TransportContext) -> None:
        self.context = context

    @abstractmethod
    def open_writer(self, endpoint: Endpoint) -> Writer:
        """The writer that feeds this transport's subscribers of ``endpoint``."""

    @abstractmethod
    def open_reader(self, endpoint: Endpoint, wake: Wake) -> Reader:
        """The reader that drains this transport's publishers of ``endpoint``; ``wake`` runs
        when it may have data."""

    def prepare(self, nodes: list[str]) -> None:
        """Open, before ``nodes`` run, what their peers must see early (writers to other hosts,
        matched by remote readers meanwhile)."""
        return None

    def wait_source(self, node: str) -> WaitSource | None:
        """What ``node``'s executor blocks on for this transport's readers, or None when they wake
        the executor through its condition."""
        return None

    def wait_matched(self, timeout: float) -> list[str]:
        """Wait until every subscriber the plan expects has matched this transport's writers; the
        channels still short after ``timeout`` (logged)."""
        return []

    def linger(self) -> list[str]:
        """The process' nodes have all returned: keep reliable writers until their subscribers
        took what was published; what was given up, as error lines naming topic and subscriber."""
        return []

    def parameter(self, node: str, name: str) -> Any:
        """Parameter ``name`` of ``node`` from the parameter server this transport's peers share
        (ROS 1's master); KeyError when it has none."""
        raise KeyError(name)

    @abstractmethod
    def close(self) -> None: ...


def register(kind: str, where: str) -> None:
    """Make ``kind`` (an edge's transport in the plan) open through ``where`` ("module:Class")."""
    if ":" not in where:
        raise TransportError(f"a transport must be registered as 'module:Class', not {where!r}")
    with _registry_lock:
        _REGISTRY[kind] = where
        _loaded.pop(kind, None)


def registered() -> list[str]:
    """Every kind of edge a transport is registered for."""
    with _registry_lock:
        return sorted(_REGISTRY)


def transport_class(kind: str) -> type[Transport]:
    """The transport registered for ``kind``, its module imported now if it was not yet."""
    with _registry_lock:
        cls = _loaded.get(kind)
        where = _REGISTRY.get(kind)
    if cls is not None:
        return cls
    if where is None:
        raise TransportError(f"no transport is registered for edges of kind {kind!r} "
                        f"(registered: {', '.join(registered())})")
    module_name, _, attr = where.partition(":")
    found = getattr(importlib.import_module(module_name), attr, None)
    if not (isinstance(found, type) and issubclass(found, Transport)):
        raise TransportError(f"transport {kind!r} is registered as {where!r}, which is not a Transport subclass")
    with _registry_lock:
        _loaded[kind] = found
    return found
