"""Message layer: types from .msg/.srv/.action files, CDR codecs, read-only delivery."""

from ._definitions import find_packages, read_package
from ._layout import ArrayField, FlatLayout, LayoutField, array_fields, flat_layout, get_path, set_path
from ._message import FrozenMessage, LoanBuffer, Message, copy, default_maker, freeze, hand_over, loaned_array
from ._registry import ActionType, ServiceType, TypeRegistry, normalize_typename, registry
from ._validate import convert_array, validate

__all__ = [
    "ActionType",
    "ArrayField",
    "FlatLayout",
    "FrozenMessage",
    "LayoutField",
    "LoanBuffer",
    "Message",
    "ServiceType",
    "TypeRegistry",
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
    "set_path",
    "validate",
]
