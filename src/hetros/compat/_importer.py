"""The finder that serves ``rclpy`` (hetros.compat.rclpy) and ROS message packages (``std_msgs.msg`` ->
``hetros.interfaces.std_msgs.msg``) in hetros's processes."""

from __future__ import annotations

import importlib
import importlib.machinery
import sys
import threading
import types
from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..msg import registry
from . import _flavour

# module names served from hetros.compat (the shims), and their prefix there
_SHIMS = ("rclpy", "rospy", "ament_index_python", "launch", "launch_ros", "launch_xml", "launch_yaml", "tf2_py",
          "message_filters", "cv_bridge",
          "tf2_ros", "tf2_geometry_msgs")
_KINDS = ("msg", "srv", "action")
# the helpers beside the message packages that ROS code imports: rospy's sensor_msgs.point_cloud2, rclpy's
# sensor_msgs_py.point_cloud2 (one implementation, hetros.compat.point_cloud2)
_HELPERS = ("sensor_msgs.point_cloud2", "sensor_msgs_py", "sensor_msgs_py.point_cloud2")


# The loaders and the finder follow importlib's protocols without subclassing ``importlib.abc``: in
# Python 3.11 that module imports importlib.resources, and with it tempfile, shutil, zipfile, bz2 and lzma,
# about 1 MB in every worker.
if TYPE_CHECKING:
    from importlib.abc import Loader as _Loader
else:
    _Loader = object


class _Alias(_Loader):
    """Loads a module that already exists under another name (the shim, or a hetros interface module)."""

    def __init__(self, target: str) -> None:
        self.target = target

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        return importlib.import_module(self.target)

    def exec_module(self, module: types.ModuleType) -> None:
        return None


class _RosNames:
    def __init__(self) -> None:
        self._busy = threading.local()

    def find_spec(self, fullname: str, path: Sequence[str] | None,
                  target: types.ModuleType | None = None) -> importlib.machinery.ModuleSpec | None:
        top = fullname.split(".", 1)[0]
        if top in _SHIMS:
            return self._spec(fullname, f"{__package__}.{fullname}")
        if fullname in _HELPERS:
            spec = importlib.machinery.ModuleSpec(fullname, _Helper(), is_package=fullname == "sensor_msgs_py")
            if fullname == "sensor_msgs_py":
                spec.submodule_search_locations = []
            return spec
        parts = fullname.split(".")
        if len(parts) > 2 or getattr(self._busy, "on", False):
            return None  # busy: the registry, asked below, imports modules of its own
        self._busy.on = True
        try:
            known = top in _packages()
        finally:
            self._busy.on = False
        if not known:
            return None
        if len(parts) == 2 and parts[1] not in _KINDS:
            return None
        spec = importlib.machinery.ModuleSpec(fullname, _Interfaces(), is_package=True)
        spec.submodule_search_locations = []
        return spec

    @staticmethod
    def _spec(fullname: str, target: str) -> importlib.machinery.ModuleSpec:
        spec = importlib.machinery.ModuleSpec(fullname, _Alias(target), is_package=True)
        spec.submodule_search_locations = []
        return spec


class _Helper(_Loader):
    """A helper module of ROS's message packages (see ``_HELPERS``)."""

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        from . import point_cloud2

        if spec.name == "sensor_msgs.point_cloud2":
            module: types.ModuleType = point_cloud2.ros1_module()
            return module
        if spec.name == "sensor_msgs_py":
            package = types.ModuleType(spec.name, "sensor_msgs_py, as hetros serves it: its point_cloud2")
            package.__path__ = []
            return package
        return point_cloud2

    def exec_module(self, module: types.ModuleType) -> None:
        return None


class _Interfaces(_Loader):
    """``std_msgs.msg`` (or ``.srv``, ``.action``) with every type of the package in it, so that ``from
    rospy_tutorials.srv import *`` works too; a service's request and response also under ROS 1's names
    (``AddTwoIntsRequest``), an action's parts under actionlib's (``FibonacciGoal``). Types come in
    rclpy's flavour (:mod:`hetros.compat._flavour`)."""

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        module = types.ModuleType(spec.name)
        module.__path__ = []
        return module

    def exec_module(self, module: types.ModuleType) -> None:
        parts = module.__name__.split(".")
        if len(parts) == 1:
            return
        source = importlib.import_module(f"hetros.interfaces.{module.__name__}")
        names: dict[str, object] = {}
        suffixes = {"srv": ("Request", "Response"), "action": ("Goal", "Result", "Feedback")}.get(parts[1], ())
        for name in dir(source):
            value = _flavour.served(getattr(source, name))
            names[name] = value
            for part in suffixes:
                names[f"{name}{part}"] = getattr(value, part)
        module.__dict__.update(names, __all__=sorted(names))


_known: tuple[tuple[int, int, int], frozenset[str]] = ((-1, -1, -1), frozenset())


def _packages() -> frozenset[str]:
    """The interface packages the process' registry knows (shipped, rosbags', the project's); worked out
    again only when the registry grew, since every import in the process asks."""
    global _known
    types_ = registry()
    key = (len(types_.fielddefs), len(types_.services), len(types_.actions))
    if key != _known[0]:
        names = {name.split("/", 1)[0] for name in types_.fielddefs}
        names |= {name.split("/", 1)[0] for name in types_.services}
        names |= {name.split("/", 1)[0] for name in types_.actions}
        _known = (key, frozenset(names))
    return _known[1]


_FINDER = _RosNames()


def install() -> None:
    """Serve ``rclpy`` and ROS message packages in this process (idempotent)."""
    if _FINDER not in sys.meta_path:
        _packages()  # the registry made before the finder asks it from inside an import
        sys.meta_path.insert(0, _FINDER)
