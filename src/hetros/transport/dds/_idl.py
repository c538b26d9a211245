"""DDS type descriptions of ROS 2 types, for the cyclonedds binding's topics.

hetros writes and reads the samples' bytes itself (its generated CDR codecs), so
these classes never serialize anything: they exist because a DDS topic needs a
type, and its name and shape (the XTypes type information the binding derives
from it) are what remote peers match against. Each is built once from the same
field definitions the codecs come from, so shape and bytes cannot disagree.
"""

from __future__ import annotations

import threading
from typing import Any

from cyclonedds.idl import make_idl_struct
from cyclonedds.idl import types as idl
from rosbags.interfaces import Nodetype

from ..._errors import UnknownTypeError
from ...msg import TypeRegistry
from ._names import dds_type_name

# the binding's generic IDL constructors (indexed at run time; untyped for mypy)
_bounded_str: Any = idl.bounded_str
_array: Any = idl.array
_sequence: Any = idl.sequence
_PRIMITIVES: dict[str, Any] = {
    "bool": bool, "byte": idl.byte, "char": idl.uint8, "int8": idl.int8, "uint8": idl.uint8,
    "int16": idl.int16, "uint16": idl.uint16, "int32": idl.int32, "uint32": idl.uint32,
    "int64": idl.int64, "uint64": idl.uint64, "float32": idl.float32, "float64": idl.float64,
}
# rmw_cyclonedds puts (client id, sequence number) in front of every request and reply
REQUEST_HEADER_FIELDS = (("client_guid", idl.uint64), ("sequence_number", idl.int64))

_lock = threading.Lock()
_cache: dict[tuple[int, str, bool], Any] = {}


def idl_type(types: TypeRegistry, typename: str, request_header: bool = False) -> Any:
    """The IdlStruct of ``typename`` named as ROS 2 names it (with rmw_cyclonedds' request
    header fields first when it is a service's request or reply)."""
    key = (id(types), typename, request_header)
    with _lock:
        if key not in _cache:
            _cache[key] = _build(types, typename, request_header)
        return _cache[key]


def _build(types: TypeRegistry, typename: str, request_header: bool) -> Any:
    if typename not in types.fielddefs:
        raise UnknownTypeError(f"unknown message type {typename!r}: ship its package under 'messages:'")
    _consts, fields = types.fielddefs[typename]
    members: dict[str, Any] = dict(REQUEST_HEADER_FIELDS) if request_header else {}
    members |= {name: _field(types, desc, f"{typename}.{name}") for name, desc in fields}
    name = typename.replace("/", "_") + ("_with_request_header" if request_header else "")
    # the DDS type name is given at creation: the binding announces that one, not a later attribute
    return make_idl_struct(name, dds_type_name(typename), members)


def _field(types: TypeRegistry, desc: Any, where: str) -> Any:
    kind, rest = desc
    if kind == Nodetype.BASE:
        base, bound = rest
        if base == "string":
            return _bounded_str[bound] if bound else str
        if base not in _PRIMITIVES:
            raise UnknownTypeError(f"{where}: ROS 2 type {base!r} has no DDS mapping in hetros "
                                   "(wstring is not carried); use string")
        return _PRIMITIVES[base]
    if kind == Nodetype.NAME:
        built = _cache.get((id(types), rest, False))
        return built if built is not None else _nested(types, rest)
    element = _field(types, rest[0], where)
    if kind == Nodetype.ARRAY:
        return _array[element, rest[1]]
    return _sequence[element, rest[1]] if rest[1] else _sequence[element]


def _nested(types: TypeRegistry, typename: str) -> Any:
    built = _build(types, typename, False)
    _cache[(id(types), typename, False)] = built  # the caller holds the lock
    return built
