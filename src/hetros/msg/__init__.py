"""Message layer: types from .msg/.srv/.action files, CDR codecs, read-only delivery."""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports
from ._layout import ArrayField, FlatLayout, LayoutField, array_fields, flat_layout, get_path, set_path
from ._message import FrozenMessage, LoanBuffer, Message, copy, default_maker, freeze, hand_over, loaned_array
from ._registry import (
    ActionKind,
    ActionType,
    ServiceKind,
    ServiceType,
    TypeRegistry,
    action_type,
    init_source,
    normalize_typename,
    registry,
    service_type,
)
from ._ros1 import ros1_store
from ._validate import convert_array, validate

if TYPE_CHECKING:
    from ._codegen import build_package_modules
    from ._compiled import wanted
    from ._convert import DEFAULT_TRUNCATE_LENGTH, from_plain, to_plain
    from ._definitions import find_packages, read_package
    from ._stubs import shipped_stubs, user_stubs


# shared with other packages, loaded on first use (a worker must not pay for what it does not run)
_LAZY = {
    "DEFAULT_TRUNCATE_LENGTH": "._convert",
    "build_package_modules": "._codegen",
    "find_packages": "._definitions",
    "read_package": "._definitions",
    "from_plain": "._convert",
    "shipped_stubs": "._stubs",
    "to_plain": "._convert",
    "user_stubs": "._stubs",
    "wanted": "._compiled",
}


__getattr__ = lazy_exports(__name__, _LAZY)


__all__ = [
    "DEFAULT_TRUNCATE_LENGTH",
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
    "build_package_modules",
    "convert_array",
    "copy",
    "default_maker",
    "find_packages",
    "flat_layout",
    "freeze",
    "from_plain",
    "get_path",
    "hand_over",
    "init_source",
    "loaned_array",
    "normalize_typename",
    "read_package",
    "registry",
    "ros1_store",
    "service_type",
    "set_path",
    "shipped_stubs",
    "to_plain",
    "user_stubs",
    "validate",
    "wanted",
]
