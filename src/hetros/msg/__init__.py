"""Message layer: types from .msg/.srv/.action files, CDR codecs, read-only delivery."""

from ._definitions import find_packages, read_package
from ._message import FrozenMessage, Message, freeze
from ._registry import ActionType, ServiceType, TypeRegistry, normalize_typename, registry

__all__ = [
    "ActionType",
    "FrozenMessage",
    "Message",
    "ServiceType",
    "TypeRegistry",
    "find_packages",
    "freeze",
    "normalize_typename",
    "read_package",
    "registry",
]

from ._layout import ArrayField, FlatLayout, LayoutField, array_fields, flat_layout

__all__ += ["ArrayField", "FlatLayout", "LayoutField", "array_fields", "flat_layout"]
