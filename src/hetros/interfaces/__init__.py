"""Importable message, service and action types.

``from hetros.interfaces.std_msgs.msg import String`` works for every type in
the process' registry: the standard ROS 2 packages rosbags carries, the
packages hetros ships (``example_interfaces``) and user packages loaded from a
project's ``messages:`` folders. The modules are made on import by a finder,
so nothing is generated ahead of time for running; what a type checker reads are the stubs
(``<package>/msg.pyi``...) beside this file for the packages above, and those
``hetros msg stubs`` writes for a project's own.
"""

from __future__ import annotations

import importlib.machinery
import sys
import types
from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..msg import registry

_PREFIX = __name__ + "."


class _InterfaceModule(types.ModuleType):
    """``hetros.interfaces.<pkg>.<kind>``: attributes resolve to registry types lazily."""

    def __init__(self, name: str, package: str, kind: str) -> None:
        super().__init__(name)
        self._package = package
        self._kind = kind
        self.__path__: list[str] = []

    def __getattr__(self, attr: str) -> object:
        if attr.startswith("__"):
            raise AttributeError(attr)
        reg = registry()
        full = f"{self._package}/{self._kind}/{attr}"
        value: object
        if self._kind == "srv" and full in reg.services:
            value = reg.services[full]
        elif self._kind == "action" and full in reg.actions:
            value = reg.actions[full]
        elif full in reg.fielddefs:
            value = reg.get(full)
        else:
            raise AttributeError(
                f"{self.__name__} has no type {attr!r}; "
                f"known: {', '.join(self.__dir__()) or 'none'}"
            )
        setattr(self, attr, value)
        return value

    def __dir__(self) -> list[str]:
        prefix = f"{self._package}/{self._kind}/"
        reg = registry()
        names = {n[len(prefix):] for n in reg.fielddefs if n.startswith(prefix)}
        if self._kind == "srv":
            names = {n[len(prefix):] for n in reg.services if n.startswith(prefix)}
        if self._kind == "action":
            names = {n[len(prefix):] for n in reg.actions if n.startswith(prefix)}
        return sorted(names)


# importlib's protocols without subclassing ``importlib.abc`` at run time: in Python 3.11 that module
# imports importlib.resources, and with it tempfile, shutil, zipfile, bz2 and lzma (about 1 MB a worker)
if TYPE_CHECKING:
    from importlib.abc import Loader as _Loader
else:
    _Loader = object


class _Finder(_Loader):
    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: types.ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if not fullname.startswith(_PREFIX):
            return None
        parts = fullname[len(_PREFIX):].split(".")
        if len(parts) > 2 or (len(parts) == 2 and parts[1] not in ("msg", "srv", "action")):
            return None
        package = parts[0]
        if not any(n.startswith(package + "/") for n in registry().fielddefs):
            return None
        return importlib.machinery.ModuleSpec(fullname, self, is_package=True)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        parts = spec.name[len(_PREFIX):].split(".")
        if len(parts) == 1:
            module = types.ModuleType(spec.name)
            module.__path__ = []
            return module
        return _InterfaceModule(spec.name, parts[0], parts[1])

    def exec_module(self, module: types.ModuleType) -> None:
        return None


# first: the typed stubs beside this file live in folders named like the packages, which the
# path finder would otherwise take for empty namespace packages
if not any(isinstance(f, _Finder) for f in sys.meta_path):
    sys.meta_path.insert(0, _Finder())
