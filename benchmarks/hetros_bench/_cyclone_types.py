"""The benchmark's CycloneDDS payload types: one per size, a fixed ``uint8`` array each.

The binding copies a fixed ``array[uint8, N]`` as one block, while ``sequence[uint8]``
goes element by element (~150 ms for 3 MiB) and a ``bytes`` field has no XTypes type
object; a fixed array per size is the binding at its best. Names follow ROS 2
(``pkg::msg::dds_::Type_``).
"""

from dataclasses import make_dataclass
from typing import Any

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, int64, uint8

_cache: dict[int, Any] = {}


def _fixed_bytes(size: int) -> Any:
    fixed: Any = array  # indexed like a generic: array[element type, length]
    return fixed[uint8, max(size, 1)]


def payload_type(size: int) -> Any:
    if size not in _cache:
        _cache[size] = make_dataclass(
            f"Payload{size}", [("stamp", int64), ("seq", int64), ("data", _fixed_bytes(size))],
            bases=(IdlStruct,), namespace={"__module__": __name__},
        )
        _cache[size].__idl_typename__ = f"hetros_bench::msg::dds_::Payload{size}_"
    return _cache[size]


def sequence_type() -> Any:
    """The binding's stock path for a ROS-like byte array: ``sequence[uint8]``, element by element."""
    if -1 not in _cache:
        _cache[-1] = make_dataclass(
            "PayloadSeq", [("stamp", int64), ("seq", int64), ("data", _sequence_of_bytes())],
            bases=(IdlStruct,), namespace={"__module__": __name__},
        )
        _cache[-1].__idl_typename__ = "hetros_bench::msg::dds_::PayloadSeq_"
    return _cache[-1]


def _sequence_of_bytes() -> Any:
    from cyclonedds.idl.types import sequence

    generic: Any = sequence
    return generic[uint8]
