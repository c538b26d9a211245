"""Messages as plain data, the way ROS 2's command line shows and reads them.

``to_plain`` gives what ``ros2 topic echo`` prints (rosidl_runtime_py's rules: nested messages
as mappings, long arrays and strings cut at a truncate length with ``'...'``, arrays replaced by
a description with ``no_arr``); ``from_plain`` builds a message from what ``ros2 topic pub``
reads (``"{data: hello}"``), naming the field of any value that does not fit.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from rosbags.interfaces import Nodetype

from .._errors import FieldValueError
from ._message import Message

if TYPE_CHECKING:
    from ._registry import TypeRegistry

# what ``ros2 topic echo`` cuts arrays and strings at unless ``--full-length``
DEFAULT_TRUNCATE_LENGTH = 128


def _field_types(types: TypeRegistry, typename: str) -> dict[str, Any]:
    return dict(types.fielddefs[typename][1])


def _describe_array(desc: Any, value: Any) -> str:
    kind, (element, bound) = desc
    element_name = element[1] if element[0] == Nodetype.NAME else element[1][0]
    if kind == Nodetype.ARRAY:
        return f"<array type: {element_name}[{bound}]>"
    return f"<sequence type: {element_name}, length: {len(value)}>"


def to_plain(types: TypeRegistry, message: Message, *, truncate_length: int | None = DEFAULT_TRUNCATE_LENGTH,
             no_arr: bool = False, no_str: bool = False) -> dict[str, Any]:
    """``message`` as nested dicts, lists and scalars, ready for ``yaml.dump``."""
    fields = _field_types(types, message.__msgtype__)
    plain: dict[str, Any] = {}
    for name in message.__fieldnames__:
        value = getattr(message, name)
        desc = fields[name.rstrip("_")] if name not in fields else fields[name]
        plain[name] = _plain_value(types, desc, value, truncate_length, no_arr, no_str)
    return plain


def _plain_value(types: TypeRegistry, desc: Any, value: Any, truncate: int | None, no_arr: bool,
                 no_str: bool) -> Any:
    kind = desc[0]
    if kind == Nodetype.NAME:
        return to_plain(types, value, truncate_length=truncate, no_arr=no_arr, no_str=no_str)
    if kind == Nodetype.BASE:
        if isinstance(value, str):
            if no_str:
                return "<string length: " + str(len(value)) + ">"
            if truncate is not None and len(value) > truncate:
                return value[:truncate] + "..."
        return value.item() if isinstance(value, np.generic) else value
    if no_arr:
        return _describe_array(desc, value)
    element = desc[1][0]
    items = list(value[:truncate] if truncate is not None else value)
    plain: list[Any]
    if element[0] == Nodetype.NAME:
        plain = [to_plain(types, item, truncate_length=truncate, no_arr=no_arr, no_str=no_str) for item in items]
    else:
        plain = [item.item() if isinstance(item, np.generic) else item for item in items]
    if truncate is not None and len(value) > truncate:
        plain.append("...")
    return plain


def from_plain(types: TypeRegistry, typename: str, data: Any, where: str = "") -> Message:
    """A message of ``typename`` from a mapping of field values (missing fields keep their defaults)."""
    where = where or typename
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise FieldValueError(f"{where} must be a mapping of field values ({{data: hello}}), not {data!r}")
    fields = _field_types(types, typename)
    cls = types.get(typename)
    names = {name.rstrip("_") if name.rstrip("_") in fields else name: name for name in cls.__fieldnames__}
    values: dict[str, Any] = {}
    for key, value in data.items():
        if key not in names:
            raise FieldValueError(f"{where} has no field {key!r}; its fields are {', '.join(names)}")
        desc = fields[key]
        values[names[key]] = _from_plain_value(types, desc, value, f"{where}.{key}")
    message: Message = cls(**values)
    message._hetros_validate(message, where)
    return message


def _from_plain_value(types: TypeRegistry, desc: Any, value: Any, where: str) -> Any:
    kind = desc[0]
    if kind == Nodetype.NAME:
        return from_plain(types, desc[1], value, where)
    if kind == Nodetype.BASE:
        return value
    element = desc[1][0]
    if not isinstance(value, list):
        raise FieldValueError(f"{where} must be a list ([1, 2, 3]), not {value!r}")
    if element[0] == Nodetype.NAME:
        return [from_plain(types, element[1], item, f"{where}[{index}]") for index, item in enumerate(value)]
    return value
