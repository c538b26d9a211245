"""hetros' message types (ROS 2's) as stock ROS 1 knows them: names, md5sums, definitions, bytes.

The ROS 1 side uses ROS 1's own definitions (rosbags' ROS1_NOETIC store): they differ
from ROS 2's (``std_msgs/Header`` has ``seq``; ``sensor_msgs/Image`` hashes to
``060021388200f6f0f447d0fcd9c64743`` in ROS 1). Serialization, md5sums and full
definitions come from rosbags. Between the two, fields map by name, recursively:

- a ROS 1 field that ROS 2 lacks gets its zero value going out and is dropped coming in
  (``Header.seq``; rospy numbers messages itself);
- a ROS 2 field that ROS 1 lacks makes the type unmappable: refused when the type is
  first used, naming the field;
- ``time``/``duration`` are ``sec``/``nanosec`` on both sides.
"""

from __future__ import annotations

import hashlib
import struct
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from ..._errors import SerializationError, UnknownTypeError
from ...msg import TypeRegistry, freeze, normalize_typename, ros1_store

Convert = Callable[[Any], Any]
Payload = bytes | memoryview
# a top-level array at least this large goes to the socket from its own memory (see Ros1Type.serialize_parts)
SPLICE_MIN = 1 << 16
_LENGTH = struct.Struct("<I")
# ROS 1 element types whose little-endian numpy arrays are their serialized bytes
_SPLICE_DTYPES = {name: np.dtype(code).newbyteorder("<") for name, code in (
    ("int8", "i1"), ("uint8", "u1"), ("int16", "i2"), ("uint16", "u2"), ("int32", "i4"), ("uint32", "u4"),
    ("int64", "i8"), ("uint64", "u8"), ("float32", "f4"), ("float64", "f8"))}
# ROS 2 gives an empty message this field; ROS 1 has none
_PLACEHOLDER = "structure_needs_at_least_one_member"

def ros1_name(typename: str) -> str:
    """``pkg/msg/Name`` -> ``pkg/Name`` (what ROS 1 puts in headers and on the master)."""
    package, _kind, name = normalize_typename(typename).split("/")
    return f"{package}/{name}"


class Ros1Kind(Protocol):
    """What a TCPROS connection needs of a message type: its ROS 1 name, md5sum, definition, codec."""

    name: str
    md5: str
    definition: str

    def serialize(self, message: Any) -> Payload: ...

    def serialize_parts(self, message: Any) -> list[Payload]:
        """The payload as pieces for one vectored write (joined, they are ``serialize(message)``)."""
        ...

    def deserialize(self, data: bytes | memoryview) -> Any: ...


class Ros1NativeType:
    """A ROS 1 type hetros has no message class for (``rosgraph_msgs/Log``): its messages are the ROS 1
    store's own objects (``ros1_store().types[typename]``), serialized by rosbags."""

    def __init__(self, typename: str) -> None:
        self.typename = normalize_typename(typename)
        self.name = ros1_name(self.typename)
        self._store = ros1_store()
        self.definition, self.md5 = self._store.generate_msgdef(self.typename, ros_version=1)
        self.cls = self._store.types[self.typename]

    def serialize(self, message: Any) -> Payload:
        return bytes(self._store.serialize_ros1(message, self.typename))

    def serialize_parts(self, message: Any) -> list[Payload]:
        return [self.serialize(message)]

    def deserialize(self, data: bytes | memoryview) -> Any:
        return self._store.deserialize_ros1(bytes(data), self.typename)


class Ros1Type:
    """One message type as both sides know it, with the converters between them."""

    def __init__(self, types: TypeRegistry, typename: str, store: Typestore | None = None) -> None:
        self.typename = normalize_typename(typename)
        self.name = ros1_name(self.typename)
        store = store or ros1_store()
        if self.typename not in store.fielddefs:
            raise UnknownTypeError(
                f"{self.typename} has no ROS 1 definition (rosbags' ROS 1 Noetic store lacks it): a topic of this "
                "type cannot be exported to ROS 1; add the ROS 1 package's .msg files or use another type"
            )
        self._types = types
        self._store = store
        self.definition, self.md5 = store.generate_msgdef(self.typename, ros_version=1)
        self._outgoing = _converter(types, store, self.typename, outgoing=True)
        self._incoming = _converter(types, store, self.typename, outgoing=False)
        # the same definition on both sides (same md5, same attribute names all the way down):
        # hetros messages go to and from ROS 1 bytes as they are, with no conversion
        self.direct = (types.store.generate_msgdef(self.typename, ros_version=1)[1] == self.md5
                       and _same_names(types, self.typename))
        self._codec = types.store if self.direct else store
        # a direct type goes through generated code (rosbags' serializer is its reference)
        self._generated = types.ros1_codec(self.typename) if self.direct else None
        self._spliceable = [(name, _SPLICE_DTYPES[desc[1][0][1][0]]) for name, desc in store.fielddefs[self.typename][1]
                            if desc[0] == Nodetype.SEQUENCE and desc[1][0][0] == Nodetype.BASE
                            and desc[1][0][1][0] in _SPLICE_DTYPES]

    def serialize(self, message: Any) -> Payload:
        """A hetros message as ROS 1 bytes (the payload of one TCPROS frame)."""
        return self._serialize(message if self.direct else self._convert(message))

    def serialize_parts(self, message: Any) -> list[Payload]:
        """The payload as pieces for one vectored write, a large array among them as its own memory.

        rosbags would copy a 6 MiB image into a fresh buffer (and page it in) before the
        socket copies it again. ROS 1 bytes are unaligned, so a top-level sequence field
        whose numpy array already holds its little-endian bytes is spliced in: rosbags
        serializes the message with that field empty (the bytes before and after it), and
        a second time with one element, so the first byte that differs is where the
        field's length goes. ``tests/unit/test_ros1_types.py`` holds the joined pieces
        against rosbags' own bytes.
        """
        ros1 = message if self.direct else self._convert(message)
        for name, dtype in self._spliceable:
            array = getattr(ros1, name)
            if (isinstance(array, np.ndarray) and array.nbytes >= SPLICE_MIN and array.dtype == dtype
                    and array.ndim == 1 and array.flags.c_contiguous):
                return self._splice(ros1, name, array)
        return [self._serialize(ros1)]

    def _splice(self, ros1: Any, name: str, array: np.ndarray[Any, Any]) -> list[Payload]:
        empty = self._serialize(_Replaced(ros1, name, array[:0]))
        one = self._serialize(_Replaced(ros1, name, array[:1]))
        mismatch = np.flatnonzero(np.frombuffer(empty, np.uint8) != np.frombuffer(one, np.uint8)[:len(empty)])
        at = int(mismatch[0])
        return [empty[:at], _LENGTH.pack(len(array)), array.data.cast("B"), empty[at + _LENGTH.size:]]

    def _convert(self, message: Any) -> Any:
        try:
            return self._outgoing(message)
        except (ValueError, TypeError, AttributeError) as exc:
            raise SerializationError(f"cannot serialize {self.typename} for ROS 1: {exc}") from exc

    def _serialize(self, ros1: Any) -> Payload:
        try:
            generated = self._generated
            if generated is not None:
                buffer = memoryview(bytearray(generated.size(ros1)))
                generated.encode(ros1, buffer)
                return buffer
            return self._codec.serialize_ros1(ros1, self.typename)
        except (ValueError, TypeError, OverflowError, AttributeError, struct.error) as exc:
            raise SerializationError(f"cannot serialize {self.typename} for ROS 1: {exc}") from exc

    def to_ros1(self, message: Any) -> Any:
        """A hetros message as a ROS 1 object of the store (to embed in a ROS 1 wrapper message)."""
        return self._outgoing(message)

    def from_ros1(self, message: Any) -> Any:
        """A ROS 1 object of the store as a read-only hetros message."""
        return freeze(self._incoming(message))

    def empty(self) -> Any:
        """A hetros message of this type with every field at its default."""
        return self._types.get(self.typename)()

    def deserialize(self, data: bytes | memoryview) -> Any:
        """ROS 1 bytes as a read-only hetros message."""
        generated = self._generated
        try:
            if generated is not None:
                return generated.decode(memoryview(data).toreadonly())  # arrays are views: read-only ones
            decoded: Any = self._codec.deserialize_ros1(data, self.typename)
        except Exception as exc:  # rosbags raises several kinds for bad bytes
            raise SerializationError(f"{len(data)} bytes do not decode as ROS 1 {self.name}: {exc}") from exc
        return freeze(decoded if self.direct else self._incoming(decoded))


    def check_frame(self, payload: bytes | memoryview) -> None:
        """Raise SerializationError unless ``payload`` is exactly one message of this type in ROS 1 bytes.

        For frames that go on as they are (hardware TCPROS: the target's deframer reads them): a
        length inside them that runs past the frame, or bytes left over, would reach the RTL.
        """
        message = self.deserialize(payload)
        ros1 = message if self.direct else self._outgoing(message)
        generated = self._generated
        size = generated.size(ros1) if generated is not None else len(self._codec.serialize_ros1(ros1, self.typename))
        if size != len(payload):
            raise SerializationError(f"{len(payload)} bytes hold one ROS 1 {self.name} of {size} bytes and "
                                     f"{len(payload) - size} bytes more")


class _Replaced:
    """``message`` as rosbags' serializer sees it, with one attribute standing in for another value."""

    __slots__ = ("_message", "_name", "_value")

    def __init__(self, message: Any, name: str, value: Any) -> None:
        self._message = message
        self._name = name
        self._value = value

    def __getattr__(self, name: str) -> Any:
        return self._value if name == self._name else getattr(self._message, name)


def _same_names(types: TypeRegistry, typename: str) -> bool:
    """Whether every field of ``typename``, nested ones too, has its definition's name as attribute
    and no ``byte``/``char`` (signed in ROS 1, an octet in ROS 2: the same md5, other values)."""
    fields = types.fielddefs[typename][1]
    names = tuple(name for name, _ in fields)
    if names != tuple(types.get(typename).__fieldnames__) or _PLACEHOLDER in names:
        return False
    for _name, desc in fields:
        element: Any = desc[1][0] if desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE) else desc
        if element[0] == Nodetype.BASE and element[1][0] in ("byte", "char"):
            return False
        if element[0] == Nodetype.NAME and not _same_names(types, str(element[1])):
            return False
    return True


def _converter(types: TypeRegistry, store: Typestore, typename: str, outgoing: bool) -> Convert:
    """A function turning one side's message of ``typename`` into the other side's."""
    ros1_fields = dict(store.fielddefs[typename][1])
    ros2_defs = dict(types.fielddefs[typename][1])
    ros2_cls = types.get(typename)
    ros1_cls = store.types[typename]
    by_lower = {name.lower(): name for name in ros1_fields}
    ros2_fields: dict[str, Any] = {}
    attrs: dict[str, str] = {}
    for (name, desc), attr in zip(ros2_defs.items(), ros2_cls.__fieldnames__, strict=True):
        if name == _PLACEHOLDER:
            continue
        # ROS 2 lower-cased some field names (CameraInfo's D, K, R, P): a unique match ignoring case
        ros1 = name if name in ros1_fields else by_lower.get(name.lower())
        if ros1 is None:
            raise UnknownTypeError(f"{typename} cannot be mapped to ROS 1: its field {name!r} has no ROS 1 "
                                   f"counterpart (ROS 1 has {', '.join(ros1_fields)})")
        ros2_fields[ros1] = desc
        attrs[ros1] = attr
    plans: list[tuple[str, str, Convert | None, Any]] = []
    for name, desc in ros1_fields.items():
        if name in ros2_fields:
            plans.append((name, attrs[name], _field_converter(types, store, desc, ros2_fields[name], outgoing,
                                                            f"{typename}.{name}"), None))
        else:
            plans.append((name, "", None, _zero(store, desc)))

    if outgoing:
        def to_ros1(message: Any) -> Any:
            values = {}
            for name, attr, convert, zero in plans:
                if not attr:
                    values[name] = zero() if callable(zero) else zero
                    continue
                value = getattr(message, attr)
                values[name] = convert(value) if convert else value
            return ros1_cls(**values)

        return to_ros1

    def to_ros2(message: Any) -> Any:
        values = {}
        for name, attr, convert, _zero_value in plans:
            if attr:
                value = getattr(message, name)
                values[attr] = convert(value) if convert else value
        return ros2_cls(**values)

    return to_ros2


def _field_converter(types: TypeRegistry, store: Typestore, ros1: Any, ros2: Any, outgoing: bool,
                     where: str) -> Convert | None:
    kind1, arg1 = ros1
    kind2, arg2 = ros2
    if kind1 != kind2:
        raise UnknownTypeError(f"{where} cannot be mapped to ROS 1: it is {_describe(ros2)} in ROS 2 "
                               f"and {_describe(ros1)} in ROS 1")
    if kind1 == Nodetype.BASE:
        if arg1[0] != arg2[0] and {arg1[0], arg2[0]} - {"byte", "uint8", "char", "int8"}:
            raise UnknownTypeError(f"{where} cannot be mapped to ROS 1: {arg2[0]} in ROS 2, {arg1[0]} in ROS 1")
        return None
    if kind1 == Nodetype.NAME:
        if arg1 != arg2:
            raise UnknownTypeError(f"{where} cannot be mapped to ROS 1: {arg2} in ROS 2, {arg1} in ROS 1")
        return _converter(types, store, arg1, outgoing)
    sub1, _length1 = arg1
    sub2, _length2 = arg2
    inner = _field_converter(types, store, sub1, sub2, outgoing, where + "[]")
    if sub1[0] == Nodetype.BASE and sub1[1][0] != "string":
        return None  # numpy arrays pass as they are
    if inner is None:
        return list
    return lambda values: [inner(value) for value in values]


def _zero(store: Typestore, desc: Any) -> Any:
    kind, arg = desc
    if kind == Nodetype.BASE:
        return "" if arg[0] == "string" else (False if arg[0] == "bool" else 0)
    if kind == Nodetype.NAME:
        cls = store.types[arg]
        fields = store.fielddefs[arg][1]
        return lambda: cls(**{name: _value(_zero(store, sub)) for name, sub in fields})
    sub, length = arg
    if sub[0] == Nodetype.BASE and sub[1][0] != "string":
        return lambda: np.zeros(length if kind == Nodetype.ARRAY else 0, np.uint8)
    return list


def _value(zero: Any) -> Any:
    return zero() if callable(zero) else zero


def _describe(desc: Any) -> str:
    kind, arg = desc
    return {Nodetype.BASE: f"a {arg[0]}" if kind == Nodetype.BASE else "", Nodetype.NAME: f"a {arg}",
            Nodetype.ARRAY: "a fixed array", Nodetype.SEQUENCE: "a sequence"}.get(kind, str(kind))


def md5_text(store: Typestore, typename: str) -> str:
    """ROS 1's md5 text of a type: constants, then fields with nested types replaced by their md5.

    ``md5(md5_text(...))`` is the type's md5sum; a service's md5sum hashes its request's text
    followed by its response's. ``tests/unit/test_ros1_types.py`` holds it against rosbags' md5
    of every ROS 1 type.
    """
    consts, fields = store.fielddefs[typename]
    lines = [f"{kind} {name}={value}" for name, kind, value in consts]
    for name, desc in fields:
        if name == _PLACEHOLDER:
            continue
        lines.append(f"{_md5_field_type(store, desc)} {name}")
    return "\n".join(lines)


def _md5_field_type(store: Typestore, desc: Any) -> str:
    kind, arg = desc
    if kind == Nodetype.BASE:
        base, bound = arg
        return f"string<={bound}" if base == "string" and bound else base
    if kind == Nodetype.NAME:
        return _TIME_TYPES.get(arg) or hashlib.md5(md5_text(store, arg).encode()).hexdigest()
    sub, length = arg
    count = "" if not length else (str(length) if kind == Nodetype.ARRAY else f"<={length}")
    if sub[0] == Nodetype.BASE:
        return f"{_md5_field_type(store, sub)}[{count}]"
    if sub[1] in _TIME_TYPES:
        return f"{_TIME_TYPES[sub[1]]}[{count}]"
    return _md5_field_type(store, sub)  # ROS 1 hashes an array of messages as the element's md5 alone


_TIME_TYPES = {"builtin_interfaces/msg/Time": "time", "builtin_interfaces/msg/Duration": "duration"}


class Ros1ServiceType:
    """A hetros service type as ROS 1 knows it: request and response types and the service md5sum.

    rosbags has no ROS 1 services, so the request and response are registered in a copy of
    the ROS 1 store from hetros' definitions, their nested types resolved against ROS 1's.
    """

    def __init__(self, types: TypeRegistry, name: str) -> None:
        service = types.get_service(name)
        self.typename = service.name
        self.name = ros1_name(normalize_typename(service.name, "srv"))
        parts = {f"{self.typename}_Request": types.fielddefs[f"{self.typename}_Request"],
                 f"{self.typename}_Response": types.fielddefs[f"{self.typename}_Response"]}
        extended = get_typestore(Stores.ROS1_NOETIC)
        try:
            extended.register({part: fielddefs for part, fielddefs in parts.items()})
        except Exception as exc:  # rosbags refuses definitions that name unknown ROS 1 types
            raise UnknownTypeError(f"{self.typename} cannot be mapped to ROS 1: {exc}") from None
        self.request = Ros1Type(types, f"{self.typename}_Request", extended)
        self.response = Ros1Type(types, f"{self.typename}_Response", extended)
        request, response = (md5_text(extended, part) for part in parts)
        self.md5 = hashlib.md5((request + response).encode()).hexdigest()
        self.request_name = f"{self.name}Request"
        self.response_name = f"{self.name}Response"
