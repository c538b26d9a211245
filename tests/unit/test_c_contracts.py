"""What the C extensions share with Python is checked against the Python definitions: the op and
primitive enums of ``_ccdr.c``, its seal modes, and the slots ``_cslot.c`` reads in place.

A renamed slot or a reordered enum would otherwise send a type silently to the slow path, or
worse, make C read the wrong field.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from hetros.msg import _compiled, _message
from hetros.transport.shm import _hotpath
from hetros.transport.shm._endpoints import _Port
from hetros.transport.shm._service import Service

SRC = Path(__file__).resolve().parents[2] / "src" / "hetros"
CCDR = (SRC / "msg" / "_ccdr.c").read_text(encoding="utf-8")
CSLOT = (SRC / "transport" / "shm" / "_cslot.c").read_text(encoding="utf-8")
C_PRIMITIVES = {"BOOL": "bool", "U8": "uint8", "I8": "int8", "I16": "int16", "U16": "uint16", "I32": "int32",
                "U32": "uint32", "I64": "int64", "U64": "uint64", "F32": "float32", "F64": "float64"}


def _enum(first: str) -> list[str]:
    """The members, in order, of the C enum whose first member is ``first``."""
    found = re.search(r"enum\s*\{\s*(" + first + r"\b[^}]*)\}", CCDR)
    assert found is not None, f"no enum starting with {first} in _ccdr.c"
    return [member.strip() for member in found.group(1).replace("\n", " ").split(",") if member.strip()]


def test_the_op_kinds_are_the_python_ones_in_order() -> None:
    members = _enum("OP_PRIM")
    assert [getattr(_compiled, "_" + member.removeprefix("OP_")) for member in members] == list(range(len(members)))


def test_the_primitive_codes_are_the_python_ones() -> None:
    members = _enum("P_BOOL")
    assert members[-1] == "P_COUNT"
    codes = {C_PRIMITIVES[member.removeprefix("P_")]: index for index, member in enumerate(members[:-1])}
    assert codes == {name: code for name, (code, _dtype) in _compiled._PRIMITIVES.items() if name in codes}
    assert set(_compiled._PRIMITIVES) - set(codes) == {"byte", "char"}  # uint8 by another name


def test_the_seal_modes_are_the_python_ones() -> None:
    assert _enum("SEAL_FREEZE") == ["SEAL_FREEZE", "SEAL_COPY", "SEAL_KEEP"]
    assert (_message._FREEZE, _message._COPY, _message._KEEP) == (0, 1, 2)


def _bound_by_c() -> set[str]:
    texts = dict(re.findall(r"\{&(str_\w+), \"(\w+)\"\}", CSLOT))
    listed = re.search(r"PyObject \*names\[\] = \{([^}]*)\}", CSLOT)
    assert listed is not None
    return {texts[name.strip()] for name in listed.group(1).split(",") if name.strip()}


def test_the_slots_the_compiled_path_binds_are_declared_and_exist() -> None:
    declared = set(_hotpath.COMPILED_SLOTS[Service]) | set(_hotpath.COMPILED_SLOTS[_Port])
    assert _bound_by_c() == declared
    for cls, names in _hotpath.COMPILED_SLOTS.items():
        assert set(names) <= set(cls.__slots__), f"{cls.__name__} lost a slot the compiled path reads"


@pytest.mark.skipif(_hotpath.take_cdr is None, reason="the compiled hot path is not built or not wanted")
def test_a_renamed_slot_is_an_error_not_a_slow_path() -> None:
    from hetros import TransportError

    class Renamed:
        __slots__ = ("_publisher", "blocking_renamed", "credits")

    with pytest.raises(TransportError, match="Renamed: the compiled path found 1 of its 3 slots"):
        _hotpath.bind_slots(Renamed, ("_publisher", "credits_at", "blocking"))
