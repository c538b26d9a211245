"""Names a package exports but loads on first use (PEP 562's module ``__getattr__``): a worker must not pay
for what its nodes do not run (the launcher, the project model, simulators, transports it has no edge on)."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any


def lazy_exports(package: str, where: dict[str, str]) -> Callable[[str], Any]:
    """The ``__getattr__`` of ``package``: each name in ``where`` from its module (relative to the package),
    imported when first asked for; any other name is an AttributeError, as usual."""

    def lookup(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(module, package), name)

    return lookup
