"""The compiled codec: the C interpreter in ``_ccdr.c`` and the programs it runs.

A program describes one message type the way the code generator in ``_cdr`` walks it
(the same rosbags field definitions): per field, its slot in the message object, its
primitive kind, fixed length or bound, and the nested type's program. The interpreter
hands every call it cannot finish (a value of an unexpected type, bytes that do not fit,
invalid UTF-8) to the generated Python function it stands in for, so errors and edge
cases stay the generated code's; ``tests/unit/test_compiled_codec.py`` checks both paths
against each other (and ``tests/unit/test_cdr.py`` the codecs against rosbags).

The extension is built by ``pip install`` when a C compiler is there. Without it, or with
``HETROS_PURE_PYTHON=1`` in the environment, every codec is the generated Python one.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype

from ._message import FrozenList, LoanBuffer, Message, _seal_array

if TYPE_CHECKING:
    from ._registry import TypeRegistry

try:  # by name: the package's lazy ``__getattr__`` would otherwise answer for it
    _ccdr: Any = importlib.import_module(f"{__package__}._ccdr")
except ImportError:  # built by pip where a C compiler is; the generated Python codecs serve otherwise
    _ccdr = None
    ARRAY_HEAD_READ = False
else:
    def _configure() -> bool:
        """Tell the interpreter what sealing needs, and let it check numpy's array head on a probe."""
        owner = np.arange(7, dtype=np.float64)
        view = owner[:]
        view.flags.writeable = False
        return bool(_ccdr.configure(LoanBuffer, _seal_array, FrozenList, owner, view, owner.ctypes.data, owner.size,
                                    owner.dtype))

    ARRAY_HEAD_READ = _configure()

# the interpreter's op kinds and primitive codes (``_ccdr.c`` has the same enums)
_PRIM, _STRING, _NESTED, _PRIM_ARRAY, _PRIM_SEQ, _STR_ARRAY, _STR_SEQ, _MSG_ARRAY, _MSG_SEQ = range(9)
_PRIMITIVES = {
    "bool": (0, "bool"), "byte": (1, "uint8"), "char": (1, "uint8"), "uint8": (1, "uint8"), "int8": (2, "int8"),
    "int16": (3, "<i2"), "uint16": (4, "<u2"), "int32": (5, "<i4"), "uint32": (6, "<u4"), "int64": (7, "<i8"),
    "uint64": (8, "<u8"), "float32": (9, "<f4"), "float64": (10, "<f8"),
}


class NotCompilable(Exception):
    """The interpreter has no op for a field of this type (``wstring``); it keeps the Python codec."""


def wanted() -> bool:
    """Whether compiled code may serve: ``HETROS_PURE_PYTHON`` (any value but 0) says no."""
    return os.environ.get("HETROS_PURE_PYTHON", "") in ("", "0")


def available() -> bool:
    """Whether codecs are compiled: the extension is built and wanted."""
    return _ccdr is not None and wanted()


def _slot(cls: type, attr: str) -> Any:
    for klass in cls.__mro__:
        if attr in vars(klass):
            return vars(klass)[attr]
    raise NotCompilable(f"{cls.__name__} has no slot {attr}")


def program(types: TypeRegistry, typename: str) -> tuple[Any, ...]:
    """The interpreter's program for ``typename`` (nested types inlined)."""
    cls = types.get(typename)
    fields: Any = types.fielddefs[typename][1]  # rosbags' (kind, argument) pairs, walked as _cdr does
    ops: list[tuple[Any, ...]] = []
    bounded_strings = False
    for attr, (_name, (kind, arg)) in zip(cls.__fieldnames__, fields, strict=True):
        descriptor = _slot(cls, attr)
        if kind == Nodetype.BASE:
            if arg[0] == "string":
                ops.append((_STRING, descriptor, 0, 0, None, None))
                bounded_strings |= bool(arg[1])
            elif arg[0] in _PRIMITIVES:
                ops.append((_PRIM, descriptor, _PRIMITIVES[arg[0]][0], 0, None, None))
            else:
                raise NotCompilable(f"{typename}.{attr}: {arg[0]}")
        elif kind == Nodetype.NAME:
            ops.append((_NESTED, descriptor, 0, 0, program(types, arg), None))
        else:
            (sub_kind, sub_arg), length = arg
            fixed = kind == Nodetype.ARRAY
            if sub_kind == Nodetype.NAME:
                ops.append((_MSG_ARRAY if fixed else _MSG_SEQ, descriptor, 0, length, program(types, sub_arg), None))
            elif sub_arg[0] == "string":
                ops.append((_STR_ARRAY if fixed else _STR_SEQ, descriptor, 0, length, None, None))
                bounded_strings |= bool(sub_arg[1])
            elif sub_arg[0] in _PRIMITIVES:
                code, dtype = _PRIMITIVES[sub_arg[0]]
                ops.append((_PRIM_ARRAY if fixed else _PRIM_SEQ, descriptor, code, length, None, np.dtype(dtype)))
            else:
                raise NotCompilable(f"{typename}.{attr}: {sub_arg[0]}")
    return (cls, cls._frozen_class, vars(Message)["_hetros_loan"], bounded_strings, tuple(ops))


def compile_codec(types: TypeRegistry, typename: str, ros1: bool, size: Callable[..., Any],
                  encode: Callable[..., Any], decode: Callable[..., Any],
                  size_lean: Callable[..., Any] | None = None, encode_lean: Callable[..., Any] | None = None) -> Any:
    """The compiled codec of ``typename`` standing in for these generated functions.

    Raises NotCompilable when the interpreter has no op for one of its fields.
    """
    assert _ccdr is not None
    return _ccdr.Codec(program(types, typename), ros1, np.frombuffer, FrozenList, size=size, encode=encode,
                       size_lean=size_lean, encode_lean=encode_lean, decode=decode)


def _stand_in(types: TypeRegistry, typename: str, role: str, fallback: Callable[..., Any]) -> Any:
    """The interpreter's ``role`` method for ``typename`` in front of ``fallback`` (``fallback``
    itself when the extension is missing or has no op for one of the type's fields)."""
    if _ccdr is None:
        return fallback
    try:
        spec = program(types, typename)
    except NotCompilable:
        return fallback
    return getattr(_ccdr.Codec(spec, False, np.frombuffer, FrozenList, **{role: fallback}), role)


def compile_validator(types: TypeRegistry, typename: str, validate: Callable[..., None]) -> Callable[..., None]:
    """The compiled validator of ``typename``, standing in for the generated ``validate``.

    It accepts a message the generated validator would pass unchanged (exact types, in range,
    arrays of the field's dtype and length); anything else, it hands to ``validate``, which
    converts, refuses with the field's path, or accepts.
    """
    checker: Callable[..., None] = _stand_in(types, typename, "validate", validate)
    return checker


def compile_sealer(types: TypeRegistry, typename: str, seal: Callable[[Message, int], Message]
                   ) -> Callable[[Message, int], Message]:
    """The compiled sealer of ``typename``, standing in for the generated ``seal``.

    It seals a message of the type's own class as ``seal`` does (nested messages of their
    own classes inline, others through their sealers) and hands it any other object.
    Arrays: loaned ones become read-only; under ``_KEEP`` the caller's are left alone; the
    other cases go through ``_message._seal_array``, as in the generated code.
    """
    sealer: Callable[[Message, int], Message] = _stand_in(types, typename, "seal", seal)
    return sealer


def compile_copier(types: TypeRegistry, typename: str, copy: Callable[[Message], Any]) -> Callable[[Message], Any]:
    """The compiled copier of ``typename``, standing in for ``_message._copy_reference``.

    It copies a message whose values are all as validation accepts them (strings and numbers
    shared, arrays and lists copied, nested messages copied alike) and hands ``copy`` any
    other, whose generated constructor converts or keeps what it is given.
    """
    copier: Callable[[Message], Any] = _stand_in(types, typename, "copy", copy)
    return copier
