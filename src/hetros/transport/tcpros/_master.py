"""A ROS 1 master: the XML-RPC master API and parameter server that stock ROS 1 tools accept.

Registration only, as in ROS 1: nodes register publishers, subscribers and services
here, and the master tells subscribers which publishers exist (``publisherUpdate`` on
their slave API); data then flows between the nodes directly. Every call returns
``[code, status message, value]`` with code 1 (success), 0 (failure) or -1 (error).

Calls out to nodes (``publisherUpdate``, ``paramUpdate``, ``shutdown``) run on one
background thread, in order, with a short timeout: a node that does not answer never
stalls a registration.
"""

from __future__ import annotations

import os
import queue
import socket
import threading
import xmlrpc.client
from collections.abc import Callable
from typing import Any

from ..._errors import TransportError
from ..._log import get_logger
from ._xmlrpc import proxy, register, serve

log = get_logger("hetros.master")

MASTER_ID = "/master"
DEFAULT_PORT = 11311
_CALL_TIMEOUT = 2.0

Reply = tuple[int, str, Any]


def _namespace(name: str) -> str:
    """``/a/b/node`` -> ``/a/b/``."""
    return name[: name.rstrip("/").rfind("/") + 1] or "/"


def _canonical(key: str) -> str:
    key = "/" + key.strip("/")
    return key if key != "/" else "/"


# a parameter server every node reads: one value may not make it unusable for the others (a 100,000-deep
# one was accepted, and `getParam /` then failed for everyone)
MAX_PARAM_DEPTH = 64
MAX_PARAM_ITEMS = 1_000_000
MAX_PARAM_BYTES = 64 << 20


def check_parameter(key: str, value: Any) -> None:
    """Refuse a value whose nesting (with its key's), item count or text size exceeds the server's bounds.

    Walked with a stack of its own: the value may be deeper than Python's recursion allows.
    """
    base = len([p for p in key.split("/") if p])
    items = size = 0
    stack: list[tuple[Any, int]] = [(value, base)]
    while stack:
        node, depth = stack.pop()
        items += 1
        if depth > MAX_PARAM_DEPTH:
            raise ValueError(f"parameter {key} nests deeper than {MAX_PARAM_DEPTH} levels (namespaces included): "
                             "flatten it")
        if items > MAX_PARAM_ITEMS:
            raise ValueError(f"parameter {key} holds more than {MAX_PARAM_ITEMS:,} values: keep large data out of "
                             "the parameter server")
        if isinstance(node, dict):
            size += sum(len(str(k)) for k in node)
            stack.extend((child, depth + 1) for child in node.values())
        elif isinstance(node, list | tuple):
            stack.extend((child, depth + 1) for child in node)
        elif isinstance(node, str | bytes | bytearray):
            size += len(node)
        elif hasattr(node, "data") and isinstance(node.data, bytes):  # xmlrpc.client.Binary
            size += len(node.data)
        if size > MAX_PARAM_BYTES:
            raise ValueError(f"parameter {key} holds more than {MAX_PARAM_BYTES >> 20} MiB: keep large data out of "
                             "the parameter server")


class _Parameters:
    """The parameter tree: a nested dict; a dict value sets a namespace."""

    def __init__(self) -> None:
        self.root: dict[str, Any] = {}

    def get(self, key: str) -> Any:
        node: Any = self.root
        for part in filter(None, key.split("/")):
            if not isinstance(node, dict) or part not in node:
                raise KeyError(key)
            node = node[part]
        return node

    def has(self, key: str) -> bool:
        try:
            self.get(key)
        except KeyError:
            return False
        return True

    def set(self, key: str, value: Any) -> None:
        check_parameter(key, value)
        parts = [p for p in key.split("/") if p]
        if not parts:
            if not isinstance(value, dict):
                raise ValueError("the root namespace can only be set to a dictionary")
            self.root = dict(value)
            return
        node = self.root
        for part in parts[:-1]:
            child = node.get(part)
            if not isinstance(child, dict):
                child = node[part] = {}
            node = child
        node[parts[-1]] = value

    def delete(self, key: str) -> None:
        parts = [p for p in key.split("/") if p]
        if not parts:
            raise KeyError(key)
        node: Any = self.get("/".join(parts[:-1]))
        if not isinstance(node, dict) or parts[-1] not in node:
            raise KeyError(key)
        del node[parts[-1]]

    def names(self) -> list[str]:
        found: list[str] = []

        def walk(prefix: str, node: dict[str, Any]) -> None:
            for name, value in node.items():
                if isinstance(value, dict) and value:
                    walk(f"{prefix}{name}/", value)
                else:
                    found.append(prefix + name)

        walk("/", self.root)
        return found


class MasterState:
    """Who publishes, subscribes and serves what; the parameters; the nodes' slave APIs.

    Every method is one master API call (its XML-RPC name), returning ``(code, message,
    value)``; ``_call`` queues calls out to nodes. Guarded by one lock.
    """

    def __init__(self, uri: str, call_node: Callable[[str, str, tuple[Any, ...]], None]) -> None:
        self._uri = uri
        self._call = call_node
        self._lock = threading.RLock()
        self._nodes: dict[str, str] = {}
        self._publishers: dict[str, dict[str, str]] = {}
        self._subscribers: dict[str, dict[str, str]] = {}
        self._services: dict[str, tuple[str, str, str]] = {}
        self._types: dict[str, str] = {}
        self._params = _Parameters()
        self._param_subscribers: dict[str, dict[str, str]] = {}

    # -- nodes -----------------------------------------------------------------------------

    def _node(self, caller_id: str, api: str) -> None:
        """Record a node's slave API; a new process under a known name replaces the old one."""
        old = self._nodes.get(caller_id)
        if old is not None and old != api:
            log.info("node %s registered again from %s: shutting down the one at %s", caller_id, api, old)
            self._forget(caller_id)
            self._call(old, "shutdown", (MASTER_ID, f"new node registered with the same name {caller_id}"))
        self._nodes[caller_id] = api

    def _forget(self, caller_id: str) -> None:
        for table in (self._publishers, self._subscribers, self._param_subscribers):
            for registered in table.values():
                registered.pop(caller_id, None)
        for name in [n for n, (owner, _u, _a) in self._services.items() if owner == caller_id]:
            del self._services[name]
        self._nodes.pop(caller_id, None)

    def lookupNode(self, caller_id: str, node_name: str) -> Reply:
        with self._lock:
            api = self._nodes.get(node_name)
        return (1, f"node api for {node_name}", api) if api else (-1, f"unknown node [{node_name}]", "")

    def getUri(self, caller_id: str) -> Reply:
        return 1, "", self._uri

    def getPid(self, caller_id: str) -> Reply:
        return 1, "", os.getpid()

    # -- topics ----------------------------------------------------------------------------

    def registerPublisher(self, caller_id: str, topic: str, topic_type: str, caller_api: str) -> Reply:
        with self._lock:
            self._node(caller_id, caller_api)
            self._publishers.setdefault(topic, {})[caller_id] = caller_api
            self._types[topic] = topic_type
            self._publishers_changed(topic)
            subscribers = list(self._subscribers.get(topic, {}).values())
        return 1, f"Registered [{caller_id}] as publisher of [{topic}]", subscribers

    def unregisterPublisher(self, caller_id: str, topic: str, caller_api: str) -> Reply:
        with self._lock:
            registered = self._publishers.get(topic, {})
            if registered.get(caller_id) != caller_api:
                return 1, f"[{caller_id}] is not a publisher of [{topic}]", 0
            del registered[caller_id]
            self._publishers_changed(topic)
        return 1, f"Unregistered [{caller_id}] as publisher of [{topic}]", 1

    def _publishers_changed(self, topic: str) -> None:
        publishers = list(self._publishers.get(topic, {}).values())
        for api in self._subscribers.get(topic, {}).values():
            self._call(api, "publisherUpdate", (MASTER_ID, topic, publishers))

    def registerSubscriber(self, caller_id: str, topic: str, topic_type: str, caller_api: str) -> Reply:
        with self._lock:
            self._node(caller_id, caller_api)
            self._subscribers.setdefault(topic, {})[caller_id] = caller_api
            if topic_type != "*" or topic not in self._types:
                self._types.setdefault(topic, topic_type)
            publishers = list(self._publishers.get(topic, {}).values())
        return 1, f"Subscribed to [{topic}]", publishers

    def unregisterSubscriber(self, caller_id: str, topic: str, caller_api: str) -> Reply:
        with self._lock:
            registered = self._subscribers.get(topic, {})
            if registered.get(caller_id) != caller_api:
                return 1, f"[{caller_id}] is not a subscriber of [{topic}]", 0
            del registered[caller_id]
        return 1, f"Unsubscribed [{caller_id}] from [{topic}]", 1

    def getPublishedTopics(self, caller_id: str, subgraph: str) -> Reply:
        prefix = subgraph if not subgraph or subgraph.endswith("/") else subgraph + "/"
        with self._lock:
            topics = [[t, self._types.get(t, "*")] for t, nodes in self._publishers.items()
                      if nodes and t.startswith(prefix)]
        return 1, "current topics", topics

    def getTopicTypes(self, caller_id: str) -> Reply:
        with self._lock:
            return 1, "current topic types", [[t, kind] for t, kind in self._types.items()]

    def getSystemState(self, caller_id: str) -> Reply:
        with self._lock:
            publishers = [[t, sorted(nodes)] for t, nodes in self._publishers.items() if nodes]
            subscribers = [[t, sorted(nodes)] for t, nodes in self._subscribers.items() if nodes]
            services = [[name, [owner]] for name, (owner, _u, _a) in self._services.items()]
        return 1, "current system state", [publishers, subscribers, services]

    # -- services --------------------------------------------------------------------------

    def registerService(self, caller_id: str, service: str, service_api: str, caller_api: str) -> Reply:
        with self._lock:
            self._node(caller_id, caller_api)
            self._services[service] = (caller_id, service_api, caller_api)
        return 1, f"Registered [{caller_id}] as provider of [{service}]", 1

    def unregisterService(self, caller_id: str, service: str, service_api: str) -> Reply:
        with self._lock:
            current = self._services.get(service)
            if current is None or current[1] != service_api:
                return 1, f"[{caller_id}] is not the provider of [{service}]", 0
            del self._services[service]
        return 1, f"Unregistered [{caller_id}] as provider of [{service}]", 1

    def lookupService(self, caller_id: str, service: str) -> Reply:
        with self._lock:
            current = self._services.get(service)
        return (1, f"rosrpc URI: [{current[1]}]", current[1]) if current else (-1, "no provider", "")

    # -- parameters ------------------------------------------------------------------------

    def _resolve(self, caller_id: str, key: str) -> str:
        return _canonical(key if key.startswith("/") else _namespace(caller_id) + key)

    def getParam(self, caller_id: str, key: str) -> Reply:
        key = self._resolve(caller_id, key)
        with self._lock:
            try:
                return 1, f"Parameter [{key}]", self._params.get(key)
            except KeyError:
                return -1, f"Parameter [{key}] is not set", 0

    def hasParam(self, caller_id: str, key: str) -> Reply:
        key = self._resolve(caller_id, key)
        with self._lock:
            return 1, key, self._params.has(key)

    def setParam(self, caller_id: str, key: str, value: Any) -> Reply:
        key = self._resolve(caller_id, key)
        with self._lock:
            try:
                self._params.set(key, value)
            except ValueError as exc:
                return -1, str(exc), 0
            self._params_changed(key)
        return 1, f"parameter {key} set", 0

    def deleteParam(self, caller_id: str, key: str) -> Reply:
        key = self._resolve(caller_id, key)
        with self._lock:
            try:
                self._params.delete(key)
            except KeyError:
                return -1, f"parameter [{key}] is not set", 0
            self._params_changed(key)
        return 1, f"parameter {key} deleted", 0

    def searchParam(self, caller_id: str, key: str) -> Reply:
        """The closest ``key`` up the caller's namespaces (ROS 1's upward search)."""
        if key.startswith("/"):
            with self._lock:
                found = self._params.has(key)
            return (1, f"Found [{key}]", key) if found else (-1, f"Cannot find parameter [{key}]", "")
        head, _, rest = key.partition("/")
        namespace = _namespace(caller_id)
        with self._lock:
            while True:
                if self._params.has(namespace + head):
                    full = namespace + key
                    return 1, f"Found [{full}]", full.rstrip("/") if rest == "" else full
                if namespace == "/":
                    return -1, f"Cannot find parameter [{key}] in an upwards search", ""
                namespace = _namespace(namespace.rstrip("/"))

    def subscribeParam(self, caller_id: str, caller_api: str, key: str) -> Reply:
        key = self._resolve(caller_id, key)
        with self._lock:
            self._node(caller_id, caller_api)
            self._param_subscribers.setdefault(key, {})[caller_id] = caller_api
            try:
                value = self._params.get(key)
            except KeyError:
                value = {}
        return 1, f"Subscribed to parameter [{key}]", value

    def unsubscribeParam(self, caller_id: str, caller_api: str, key: str) -> Reply:
        key = self._resolve(caller_id, key)
        with self._lock:
            removed = self._param_subscribers.get(key, {}).pop(caller_id, None) is not None
        return 1, f"Unsubscribed from parameter [{key}]", int(removed)

    def getParamNames(self, caller_id: str) -> Reply:
        with self._lock:
            return 1, "Parameter names", self._params.names()

    def _params_changed(self, key: str) -> None:
        """Tell each subscriber of ``key``, of a namespace above it or a key below it."""
        for subscribed, nodes in self._param_subscribers.items():
            related = subscribed == key or subscribed.startswith(key.rstrip("/") + "/") or \
                key.startswith(subscribed.rstrip("/") + "/")
            if not related or not nodes:
                continue
            try:
                value = self._params.get(subscribed)
            except KeyError:
                value = {}
            for api in nodes.values():
                self._call(api, "paramUpdate", (MASTER_ID, subscribed + "/" if isinstance(value, dict) else subscribed,
                                                value))


class Master:
    """``hetros master``: serves the master API on ``host:port`` until ``close``."""

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT) -> None:
        try:
            self._server = serve(host, port)
        except OSError as exc:
            raise TransportError(
                f"cannot serve a ROS master on {host}:{port}: {exc.strerror or exc}; is another roscore or "
                "hetros master running there? choose another --port"
            ) from None
        bound_host, bound_port = self._server.server_address[:2]
        shown = socket.gethostname() if host in ("0.0.0.0", "") else str(bound_host)
        self.uri = f"http://{shown}:{bound_port}/"
        self._calls: queue.Queue[tuple[str, str, tuple[Any, ...]] | None] = queue.Queue()
        self.state = MasterState(self.uri, lambda api, method, args: self._calls.put((api, method, args)))
        register(self._server, self.state)  # made after binding: the URI names the bound port
        self._threads = [threading.Thread(target=self._server.serve_forever, name="hetros-master", daemon=True),
                         threading.Thread(target=self._call_nodes, name="hetros-master-calls", daemon=True)]
        for thread in self._threads:
            thread.start()
        log.info("ROS master at %s", self.uri)

    def _call_nodes(self) -> None:
        while (call := self._calls.get()) is not None:
            api, method, args = call
            try:
                getattr(proxy(api, _CALL_TIMEOUT), method)(*args)
            except (OSError, xmlrpc.client.Error) as exc:
                log.debug("%s on %s failed: %s", method, api, exc)

    def close(self) -> None:
        """Stop serving; updates not yet sent to nodes are dropped (a master that goes away owes nobody a
        ``publisherUpdate``), and one under way is left to its daemon thread, so SIGTERM ends the master
        within a second even while a node it calls no longer answers."""
        self._server.shutdown()
        self._server.server_close()
        while True:
            try:
                self._calls.get_nowait()
            except queue.Empty:
                break
        self._calls.put(None)
        for thread in self._threads:
            thread.join(timeout=0.5)
