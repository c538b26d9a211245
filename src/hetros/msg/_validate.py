"""One rule for field values in every mapping, checked when a message is handed over.

Between threads a message object travels as it is; between processes it is
serialized. Without a check, ``String(data=5)`` would reach a thread but break a
process, and ``Int32(data=2**40)`` would be silently different on the two sides.
So publish, service requests and responses run the type's validator first: a
small function generated once per type that checks every field's Python type and
range and names the field, the expected type and the value when one is wrong.

The rule for primitive arrays: integers (and bools) convert into any integer array
when every value fits its range, integers and floats into float arrays; floats into
an integer array, strings or objects are refused instead of truncated. An array of the
field's exact dtype is used as it is.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype

from .._errors import FieldValueError

if TYPE_CHECKING:
    from ._registry import TypeRegistry

INT_RANGES = {
    "byte": (0, 255), "char": (0, 255), "int8": (-2**7, 2**7 - 1), "uint8": (0, 2**8 - 1),
    "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1), "int32": (-2**31, 2**31 - 1),
    "uint32": (0, 2**32 - 1), "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1),
}
FLOAT32_MAX = 3.4028234663852886e38

Validator = Callable[[Any, str], None]

# the numpy dtype of each primitive ROS type, as a message's arrays hold it (native byte order)
NUMPY_DTYPES = {
    "bool": "bool_", "byte": "uint8", "char": "uint8", "int8": "int8", "uint8": "uint8",
    "int16": "int16", "uint16": "uint16", "int32": "int32", "uint32": "uint32",
    "int64": "int64", "uint64": "uint64", "float32": "float32", "float64": "float64",
}


def _describe(value: object) -> str:
    text = repr(value)
    text = text if len(text) <= 60 else text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def refuse(where: str, expected: str, value: object) -> FieldValueError:
    return FieldValueError(f"{where} must be {expected}, not {_describe(value)}")


def convert_array(value: Any, dtype: np.dtype[Any], where: str, length: int = 0, bounded: bool = False
                  ) -> np.ndarray[Any, Any]:
    """``value`` as a 1-d array of ``dtype`` under the documented rule, else FieldValueError."""
    if type(value) is np.ndarray and value.dtype == dtype:
        array = value
    elif isinstance(value, (bytes, bytearray, memoryview)) and dtype.itemsize == 1:
        array = np.frombuffer(value, dtype)
    else:
        try:
            array = np.asarray(value)
        except (ValueError, TypeError):
            raise refuse(where, f"a sequence of {dtype.name}", value) from None
        if array.dtype == object or (array.ndim != 1 and array.size):
            raise refuse(where, f"a flat sequence of {dtype.name}", value)
        if array.size:
            allowed = {"b": "b", "i": "biu", "u": "biu", "f": "biuf"}.get(dtype.kind, "")
            if array.dtype.kind not in allowed:
                raise refuse(where, f"a sequence of {dtype.name} (no {array.dtype.name} values into "
                             f"{dtype.name}: they would be truncated)", value)
            if dtype.kind in "iu":
                info = np.iinfo(dtype)
                low, high = int(array.min()), int(array.max())
                if low < info.min or high > info.max:
                    raise FieldValueError(f"{where} must hold values in {info.min}..{info.max} for "
                                          f"{dtype.name}, not {low if low < info.min else high}")
        array = array.astype(dtype, copy=False).reshape(-1)
    if length and not bounded and array.size != length:
        raise FieldValueError(f"{where} must have exactly {length} elements, not {array.size}")
    if length and bounded and array.size > length:
        raise FieldValueError(f"{where} must have at most {length} elements, not {array.size}")
    return array


def check_int(value: object, base: str, where: str) -> None:
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        low, high = INT_RANGES[base]
        if low <= value <= high:
            return
        raise FieldValueError(f"{where} must be {base} ({low}..{high}), not {value}")
    raise refuse(where, f"an int ({base})", value)


def check_float(value: object, base: str, where: str) -> None:
    if isinstance(value, (float, int, np.floating, np.integer)) and not isinstance(value, (bool, np.bool_)):
        number = float(value)
        if base == "float32" and math.isfinite(number) and abs(number) > FLOAT32_MAX:
            raise FieldValueError(f"{where} must fit float32 (±{FLOAT32_MAX:.4g}), not {value}")
        return
    raise refuse(where, f"a number ({base})", value)


def check_bool(value: object, where: str) -> None:
    if not isinstance(value, (bool, np.bool_)):
        raise refuse(where, "a bool", value)


def check_str(value: object, bound: int, where: str) -> None:
    if not isinstance(value, str):
        raise refuse(where, "a str", value)
    if bound and len(value) > bound:
        raise FieldValueError(f"{where} must have at most {bound} characters, not {len(value)}")


def validate(message: Any) -> None:
    """Raise FieldValueError when a field of ``message`` holds a value its type cannot carry."""
    message._hetros_validate(message, type(message).__msgtype__.rsplit("/", 1)[-1])


def build_validator(types: TypeRegistry, typename: str) -> Validator:
    """A function that raises FieldValueError for the first wrong field of a ``typename`` message.

    A nested message of its field's own generated class is checked inline (a call per nested
    message is most of the cost of a small message); any other goes through its validator.
    """
    namespace: dict[str, Any] = {"check_int": check_int, "check_float": check_float, "check_bool": check_bool,
                                 "check_str": check_str, "convert_array": convert_array, "refuse": refuse,
                                 "np": np, "osa": object.__setattr__}
    short = typename.rsplit("/", 1)[-1]
    lines = ["def validate(m, where=" + repr(short) + "):"]
    _message_lines(types, typename, "m", "", "    ", lines, namespace, [0])
    lines.append("    pass")
    exec(compile("\n".join(lines), f"<hetros validator {typename}>", "exec"), namespace)
    validate: Validator = namespace["validate"]
    return validate


def _message_lines(types: TypeRegistry, typename: str, obj: str, path: str, indent: str, lines: list[str],
                   namespace: dict[str, Any], counter: list[int]) -> None:
    """Append the checks of every field of ``obj`` (a ``typename`` message at ``path``)."""
    _, fields = types.fielddefs[typename]
    cls = types.get(typename)
    for (_name, desc), attr in zip(fields, cls.__fieldnames__, strict=True):
        counter[0] += 1
        _field_lines(types, desc, obj, attr, f"{path}.{attr}", indent, lines, namespace, counter)


def _field_lines(types: TypeRegistry, desc: Any, obj: str, attr: str, path: str, indent: str, lines: list[str],
                 namespace: dict[str, Any], counter: list[int]) -> None:
    """Append the checks of field ``attr`` of ``obj``; ``path`` names it for errors ('.header.stamp')."""
    kind, arg = desc
    index = counter[0]
    get = f"{obj}.{attr}"
    where = f"where + {path!r}"
    if kind == Nodetype.BASE:
        base, bound = arg
        if base in INT_RANGES:
            low, high = INT_RANGES[base]
            check = f"if type(v) is not int or not {low} <= v <= {high}: check_int(v, {base!r}, {where})"
        elif base in ("float32", "float64"):
            check = f"if type(v) is not float or {base == 'float32'!r}: check_float(v, {base!r}, {where})"
        elif base == "bool":
            check = f"if type(v) is not bool: check_bool(v, {where})"
        else:
            check = f"if type(v) is not str or {bound or 0}: check_str(v, {bound or 0}, {where})"
        lines += [f"{indent}v = {get}", indent + check]
        return
    if kind == Nodetype.NAME:
        nested = f"o{index}"
        namespace[f"T{index}"] = types.get(arg)
        lines += [f"{indent}{nested} = {get}", f"{indent}if type({nested}) is T{index}:"]
        _message_lines(types, arg, nested, path, indent + "    ", lines, namespace, counter)
        lines += [f"{indent}    pass",
                  f"{indent}elif not isinstance({nested}, T{index}): raise refuse({where}, {'a ' + arg!r}, {nested})",
                  f"{indent}else: {nested}._hetros_validate({nested}, {where})"]
        return
    sub, length = arg
    bounded = kind == Nodetype.SEQUENCE
    if sub[0] == Nodetype.BASE and sub[1][0] not in ("string", "wstring"):
        namespace[f"D{index}"] = np.dtype(NUMPY_DTYPES[sub[1][0]])
        fixed = f"v.size != {length}" if not bounded and length else (f"v.size > {length}" if length else "False")
        lines += [f"{indent}v = {get}",
                  f"{indent}if type(v) is not np.ndarray or v.dtype != D{index} or {fixed}:",
                  f"{indent}    osa({obj}, {attr!r}, convert_array(v, D{index}, {where}, {length}, {bounded}))"]
        return
    lines += [f"{indent}v = {get}", f"{indent}if not isinstance(v, (list, tuple)): raise refuse({where}, 'a list', v)"]
    if length:
        lines.append(f"{indent}if {'len(v) > ' if bounded else 'len(v) != '}{length}: "
                     f"raise refuse({where}, '{'at most' if bounded else 'exactly'} {length} elements', v)")
    if sub[0] == Nodetype.BASE:
        bound = sub[1][1] or 0
        lines.append(f"{indent}for i, item in enumerate(v): check_str(item, {bound}, {where} + f'[{{i}}]') "
                     "if type(item) is not str or " + f"{bound} else None")
        return
    namespace[f"T{index}"] = types.get(sub[1])
    expected = "a " + sub[1]
    lines += [f"{indent}for i, item in enumerate(v):",
              f"{indent}    if not isinstance(item, T{index}): raise refuse({where} + f'[{{i}}]', {expected!r}, item)",
              f"{indent}    item._hetros_validate(item, {where} + f'[{{i}}]')"]
