"""A node's parameters as ROS 2 reaches them: the six services (``/ns/talker/get_parameters`` and the
rest, ``rcl_interfaces/srv``) that ``ros2 param``, rclpy's ``AsyncParameterClient`` and ``hetros param``
call.

Every node answers them on the command line's control socket; a node whose parameter services another
node of the project calls (the plan lists them under its services) serves them on the graph's transports
too. What they read and change is the node's :class:`ParameterAccess`: the project file's parameters
for a node written against hetros's API, rclpy's declared parameters (and its callbacks) for an rclpy
node.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from .._errors import ParameterError
from ..msg import registry
from ..plan import PARAMETER_SERVICES

if TYPE_CHECKING:
    from ..msg import ServiceType
    from ._node import Node

# rcl_interfaces/msg/ParameterType: the kind of a value, and the field of ParameterValue that holds it
_BOOL, _INTEGER, _DOUBLE, _STRING, _BYTES = 1, 2, 3, 4, 5
_FIELDS = {1: "bool_value", 2: "integer_value", 3: "double_value", 4: "string_value", 5: "byte_array_value",
           6: "bool_array_value", 7: "integer_array_value", 8: "double_array_value", 9: "string_array_value"}
# ROS 2 parameter names nest with dots (``camera.width``)
SEPARATOR = "."


def _message(name: str) -> Any:
    return registry().get(f"rcl_interfaces/msg/{name}")


def _service(name: str) -> Any:
    return registry().get_service(f"rcl_interfaces/srv/{name}")


class ParameterAccess(Protocol):
    """What a node's parameter services read and change."""

    def parameter_names(self) -> list[str]:
        """Every parameter's name, in the order the node gained them."""
        ...

    def parameter_value(self, name: str) -> Any:
        """The value of ``name`` (None: declared without a value); :class:`ParameterError` when the node has
        no such parameter and takes no undeclared ones."""
        ...

    def set_parameters_as_one(self, changes: list[tuple[str, Any]]) -> tuple[bool, str]:
        """Set (value None: unset) all of ``changes`` or none: (successful, reason)."""
        ...


class ProjectParameters:
    """The parameters of a node written against hetros's API: the project file's, each keeping its type
    (an integer may become a float), none added or removed while the node runs."""

    def __init__(self, node: Node) -> None:
        self._node = node

    def parameter_names(self) -> list[str]:
        return list(self._node.parameters)

    def parameter_value(self, name: str) -> Any:
        parameters = self._node.parameters
        if name not in parameters:
            raise ParameterError(f"node {self._node.name!r} has no parameter {name!r}: its parameters are the "
                                 f"project file's nodes.{self._node.name}.parameters")
        return parameters[name]

    def set_parameters_as_one(self, changes: list[tuple[str, Any]]) -> tuple[bool, str]:
        parameters = self._node.parameters
        for name, value in changes:
            if value is None:
                return False, (f"parameter {name!r} of node {self._node.name!r} cannot be unset: a hetros node's "
                               "parameters are the project file's")
            if name not in parameters:
                return False, (f"node {self._node.name!r} has no parameter {name!r}: declare it under "
                               f"nodes.{self._node.name}.parameters in the project file")
            problem = type_change_problem(self._node.name, name, parameters[name], value)
            if problem:
                return False, problem
        for name, value in changes:
            self._node.set_parameter(name, value)
        return True, ""


def type_change_problem(node: str, name: str, old: Any, new: Any) -> str:
    """Why ``name`` may not go from ``old`` to ``new`` ("" when it may): a parameter keeps its type, as
    ROS 2's statically typed ones do; an integer may become a float."""
    widened = isinstance(old, float) and isinstance(new, int) and not isinstance(new, bool)
    if old is None or type(old) is type(new) or widened:
        return ""
    if new is None:
        return f"parameter {name!r} of node {node!r} is a {type(old).__name__}: a statically typed one cannot be unset"
    return f"parameter {name!r} of node {node!r} is a {type(old).__name__}, not a {type(new).__name__}"


def kind_of(value: Any) -> int:
    """The rcl_interfaces ParameterType of a Python value (0, NOT_SET, for None or what none holds)."""
    if value is None:
        return 0
    for kind, types in ((_BOOL, bool), (_INTEGER, int), (_DOUBLE, float), (_STRING, str), (_BYTES, bytes)):
        if isinstance(value, types):
            return kind
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, list | tuple):
        items = list(value)
        if all(isinstance(v, bytes) for v in items):  # rclpy's order: an empty list is a byte array
            return _BYTES
        for kind, types in ((6, bool), (7, int), (8, float), (9, str)):
            if all(isinstance(v, types) and (types is bool or not isinstance(v, bool)) for v in items):
                return kind
    return 0


def to_value_message(value: Any) -> Any:
    """An rcl_interfaces/msg/ParameterValue holding ``value``."""

    kind = kind_of(value)
    message = _message("ParameterValue")(type=kind)
    if kind:
        held = value.tolist() if hasattr(value, "tolist") else value
        if kind == _BYTES and isinstance(held, list):
            held = b"".join(held)
        setattr(message, _FIELDS[kind], list(held) if kind == _BYTES else held)
    return message


def from_value_message(message: Any) -> Any:
    """The Python value an rcl_interfaces/msg/ParameterValue holds (None for NOT_SET); arrays as lists."""
    field = _FIELDS.get(int(message.type))
    if field is None:
        return None
    value = getattr(message, field)
    if field == "byte_array_value":
        return [bytes([b]) for b in bytes(value)]
    return value.tolist() if hasattr(value, "tolist") else (list(value) if field.endswith("array_value") else value)


def listed(names: list[str], prefixes: list[str], depth: int) -> tuple[list[str], list[str]]:
    """rcl_interfaces/srv/ListParameters as ROS 2 answers it: the names under ``prefixes`` (all when
    none), at most ``depth`` levels below them (0: every level), and the prefixes of those names."""
    def shallow(name: str) -> bool:
        return name.count(SEPARATOR) < depth

    found: list[str] = []
    found_prefixes: list[str] = []
    for name in names:
        if prefixes or depth:
            everything = not prefixes and shallow(name)
            if not everything and not any(
                    name == prefix or (name.startswith(prefix + SEPARATOR)
                                       and (depth == 0 or shallow(name[len(prefix) + 1:]))) for prefix in prefixes):
                continue
        found.append(name)
        prefix, separator, _ = name.rpartition(SEPARATOR)
        if separator and prefix not in found_prefixes:
            found_prefixes.append(prefix)
    return found, found_prefixes


class ParameterServices:
    """The handlers of one node's six parameter services, by service name; each takes the request and
    returns the response, as a hetros service handler does."""

    def __init__(self, node: Node, full_name: str, access: ParameterAccess | None = None) -> None:
        self._node = node
        self._fixed = access  # a ROS node the code made beside the project's (else the node's own access)
        handlers: dict[str, Callable[[Any], Any]] = {
            "describe_parameters": self._describe, "get_parameter_types": self._types,
            "get_parameters": self._get, "list_parameters": self._list, "set_parameters": self._set,
            "set_parameters_atomically": self._set_atomically}
        self.handlers: dict[str, tuple[ServiceType, Callable[[Any], Any]]] = {
            f"{full_name}/{service}": (registry().get_service(PARAMETER_SERVICES[service]), handler)
            for service, handler in handlers.items()}

    @property
    def _access(self) -> ParameterAccess:
        return self._fixed if self._fixed is not None else self._node.parameter_access

    def _values(self, names: list[str]) -> list[Any] | None:
        """The values of ``names``; None when one of them is not there (ROS 2 then answers with none)."""
        try:
            return [self._access.parameter_value(name) for name in names]
        except ParameterError:
            return None

    def _get(self, request: Any) -> Any:
        values = self._values(list(request.names)) or []
        return _service("GetParameters").Response(values=[to_value_message(value) for value in values])

    def _types(self, request: Any) -> Any:
        values = self._values(list(request.names)) or []
        return _service("GetParameterTypes").Response(types=[kind_of(value) for value in values])

    def _describe(self, request: Any) -> Any:
        names = list(request.names)
        values = self._values(names) or []
        return _service("DescribeParameters").Response(descriptors=[
            _message("ParameterDescriptor")(name=name, type=kind_of(value), dynamic_typing=False)
            for name, value in zip(names, values, strict=False)])

    def _list(self, request: Any) -> Any:
        names, prefixes = listed(self._access.parameter_names(), list(request.prefixes), int(request.depth))
        result = _message("ListParametersResult")(names=names, prefixes=prefixes)
        return _service("ListParameters").Response(result=result)

    def _result(self, changes: list[tuple[str, Any]]) -> Any:
        try:
            successful, reason = self._access.set_parameters_as_one(changes)
        except ParameterError as refused:
            successful, reason = False, str(refused)
        return _message("SetParametersResult")(successful=successful, reason=reason)

    def _set(self, request: Any) -> Any:
        return _service("SetParameters").Response(
            results=[self._result([(p.name, from_value_message(p.value))]) for p in request.parameters])

    def _set_atomically(self, request: Any) -> Any:
        return _service("SetParametersAtomically").Response(result=self._result(
            [(p.name, from_value_message(p.value)) for p in request.parameters]))
