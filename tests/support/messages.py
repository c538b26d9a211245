"""Random messages of any registered type, for cross-checking codecs against rosbags."""

from __future__ import annotations

import random
from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype

from hetros.msg import TypeRegistry

# rosbags packs ROS 2's ``byte`` (an octet, 0..255) as signed: the reference agrees up to 127
_INTS = {
    "byte": (0, 127), "char": (0, 255), "int8": (-128, 127), "uint8": (0, 255), "int16": (-2**15, 2**15 - 1),
    "uint16": (0, 2**16 - 1), "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1),
}
_DTYPES = {"bool": "bool", "byte": "uint8", "char": "uint8", "float32": "float32", "float64": "float64"}
_TEXT = ["", "a", "frame", "ünïcödé", "x" * 13, "map/odom", "日本"]


def random_message(types: TypeRegistry, typename: str, rnd: random.Random, depth: int = 0) -> Any:
    """A message with every field drawn at random within its type (lengths short, strings varied)."""
    cls = types.get(typename)
    _consts, fields = types.store.fielddefs[cls.__msgtype__]
    values = [_value(types, desc, rnd, depth) for _name, desc in fields]
    return cls(*values)


def _scalar(base: str, rnd: random.Random) -> Any:
    if base in _INTS:
        low, high = _INTS[base]
        return rnd.choice([low, high, 0, rnd.randint(low, high)])
    if base == "bool":
        return rnd.random() < 0.5
    if base == "float32":
        return float(np.float32(rnd.uniform(-1e6, 1e6)))
    if base == "float64":
        return rnd.choice([0.0, -1.5, rnd.uniform(-1e300, 1e300)])
    return rnd.choice(_TEXT)


def _array(base: str, count: int, rnd: random.Random) -> np.ndarray[Any, Any]:
    dtype = np.dtype(_DTYPES.get(base, base))
    if dtype.kind in "iu":
        info = np.iinfo(dtype)
        return np.array([rnd.randint(int(info.min), int(info.max)) for _ in range(count)], dtype)
    if dtype.kind == "b":
        return np.array([rnd.random() < 0.5 for _ in range(count)], dtype)
    return np.array([rnd.uniform(-1e3, 1e3) for _ in range(count)], dtype)


def _value(types: TypeRegistry, desc: Any, rnd: random.Random, depth: int) -> Any:
    kind, arg = desc
    if kind == Nodetype.BASE:
        return _scalar(arg[0], rnd)
    if kind == Nodetype.NAME:
        return random_message(types, arg, rnd, depth + 1)
    sub, length = arg
    if kind == Nodetype.ARRAY:
        count = length
    else:
        count = rnd.choice([0, 1, 2, 3, 7]) if depth < 3 else 0
        if length:
            count = min(count, length)
    if sub[0] == Nodetype.BASE and sub[1][0] != "string":
        return _array(sub[1][0], count, rnd)
    return [_value(types, sub, rnd, depth + 1) for _ in range(count)]


def cdr_body(types: TypeRegistry, typename: str, message: Any) -> bytes:
    """``message``'s CDR body, as a hardware stream carries it."""
    codec = types.codec(typename)
    buffer = bytearray(codec.size(message))
    codec.encode(message, memoryview(buffer))
    return bytes(buffer)
