"""Message layer: types from .msg/.srv/.action files, CDR codecs, read-only delivery."""

from ._definitions import find_packages, read_package
from ._layout import ArrayField, FlatLayout, LayoutField, array_fields, flat_layout, get_path, set_path
from ._message import FrozenMessage, LoanBuffer, Message, copy, default_maker, freeze, hand_over, loaned_array
from ._registry import (
    ActionKind,
    ActionType,
    ServiceKind,
    ServiceType,
    TypeRegistry,
    action_type,
    normalize_typename,
    registry,
    service_type,
)
from ._ros1 import ros1_store
from ._validate import convert_array, validate

__all__ = [
    "ActionKind",
    "ActionType",
    "ArrayField",
    "FlatLayout",
    "FrozenMessage",
    "LayoutField",
    "LoanBuffer",
    "Message",
    "ServiceKind",
    "ServiceType",
    "TypeRegistry",
    "action_type",
    "array_fields",
    "convert_array",
    "copy",
    "default_maker",
    "find_packages",
    "flat_layout",
    "freeze",
    "get_path",
    "hand_over",
    "loaned_array",
    "normalize_typename",
    "read_package",
    "registry",
    "ros1_store",
    "service_type",
    "set_path",
    "validate",
]
