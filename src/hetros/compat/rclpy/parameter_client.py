"""rclpy.parameter_client: ``AsyncParameterClient``, the client of another node's six parameter services.

The project plans the services it calls: ``hetros init`` reads ``AsyncParameterClient(node, 'name')`` and
writes the six under the calling node's ``clients:`` (``/name/get_parameters`` and the rest), and the
named node then serves them on the graph's transports.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

from ...plan import PARAMETER_SERVICES
from .node import Node
from .parameter import Parameter, parameter_dict_from_yaml_file
from .task import Future


class AsyncParameterClient:
    """Reads and sets the parameters of ``remote_node_name`` (relative names resolve under ``node``'s
    namespace, as rclpy's); each call returns a :class:`Future` of the service's response."""

    def __init__(self, node: Node, remote_node_name: str, qos_profile: Any = None,
                 callback_group: Any = None) -> None:
        from ...interfaces.rcl_interfaces import srv

        self.node = node
        self.remote_node_name = remote_node_name
        self._clients = {service: node.create_client(getattr(srv, typename.rpartition("/")[2]),
                                                     f"{remote_node_name}/{service}")
                         for service, typename in PARAMETER_SERVICES.items()}
        self._srv = srv

    def services_are_ready(self) -> bool:
        return all(client.service_is_ready() for client in self._clients.values())

    def wait_for_services(self, timeout_sec: float | None = None) -> bool:
        deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
        for client in self._clients.values():
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if not client.wait_for_service(timeout_sec=left):
                return False
        return True

    def _call(self, service: str, request: Any, callback: Callable[[Future], None] | None) -> Future:
        future: Future = self._clients[service].call_async(request)
        if callback is not None:
            future.add_done_callback(callback)
        return future

    def list_parameters(self, prefixes: list[str] | None = None, depth: int | None = None,
                        callback: Callable[[Future], None] | None = None) -> Future:
        request = self._srv.ListParameters.Request(prefixes=list(prefixes or []), depth=depth or 0)
        return self._call("list_parameters", request, callback)

    def get_parameters(self, names: list[str], callback: Callable[[Future], None] | None = None) -> Future:
        return self._call("get_parameters", self._srv.GetParameters.Request(names=list(names)), callback)

    def get_parameter_types(self, names: list[str], callback: Callable[[Future], None] | None = None) -> Future:
        return self._call("get_parameter_types", self._srv.GetParameterTypes.Request(names=list(names)), callback)

    def describe_parameters(self, names: list[str], callback: Callable[[Future], None] | None = None) -> Future:
        return self._call("describe_parameters", self._srv.DescribeParameters.Request(names=list(names)), callback)

    def set_parameters(self, parameters: Sequence[Any], callback: Callable[[Future], None] | None = None) -> Future:
        request = self._srv.SetParameters.Request(parameters=_messages(parameters))
        return self._call("set_parameters", request, callback)

    def set_parameters_atomically(self, parameters: Sequence[Any],
                                  callback: Callable[[Future], None] | None = None) -> Future:
        request = self._srv.SetParametersAtomically.Request(parameters=_messages(parameters))
        return self._call("set_parameters_atomically", request, callback)

    def delete_parameters(self, names: list[str], callback: Callable[[Future], None] | None = None) -> Future:
        """Unset each of ``names`` (a parameter set to NOT_SET is undeclared, where its node allows it)."""
        return self.set_parameters([Parameter(name) for name in names], callback)

    def load_parameter_file(self, parameter_file: str, use_wildcard: bool = False,
                            callback: Callable[[Future], None] | None = None) -> Future:
        parameters = parameter_dict_from_yaml_file(parameter_file, use_wildcard)
        return self.set_parameters(list(parameters.values()), callback)

    def load_parameter_file_atomically(self, parameter_file: str, use_wildcard: bool = False,
                                       callback: Callable[[Future], None] | None = None) -> Future:
        parameters = parameter_dict_from_yaml_file(parameter_file, use_wildcard)
        return self.set_parameters_atomically(list(parameters.values()), callback)


def _messages(parameters: Sequence[Any]) -> list[Any]:
    return [p.to_parameter_msg() if isinstance(p, Parameter) else p for p in parameters]


__all__ = ["AsyncParameterClient"]
