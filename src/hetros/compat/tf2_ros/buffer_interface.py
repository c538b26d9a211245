"""tf2_ros.buffer_interface: how ``Buffer.transform`` finds the function that moves a stamped message into
another frame (``TransformRegistration``, filled by tf2_geometry_msgs and the like) and converts between
types (``ConvertRegistration``, ``convert``). Types are keyed by their ROS name, so rclpy's, rospy's and
hetros's classes of one message type share their functions."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

from ..tf2_py import TransformException


class TypeException(TransformException):
    """No function is registered for a type."""


class NotImplementedException(TransformException):
    """A method the interface leaves to its implementation."""


def _key(cls: Any) -> str:
    return str(getattr(cls, "__msgtype__", None) or getattr(cls, "_type", None) or cls)


class TransformRegistration:
    __type_map: ClassVar[dict[str, Callable[[Any, Any], Any]]] = {}

    def print_me(self) -> None:
        print(TransformRegistration.__type_map)

    def add(self, key: Any, callback: Callable[[Any, Any], Any]) -> None:
        TransformRegistration.__type_map[_key(key)] = callback

    def get(self, key: Any) -> Callable[[Any, Any], Any]:
        found = TransformRegistration.__type_map.get(_key(key))
        if found is None:
            raise TypeException(f"Type {_key(key)} if not loaded or supported")
        return found


class ConvertRegistration:
    __to_msg_map: ClassVar[dict[str, Callable[[Any], Any]]] = {}
    __from_msg_map: ClassVar[dict[str, Callable[[Any], Any]]] = {}
    __convert_map: ClassVar[dict[tuple[str, str], Callable[[Any], Any]]] = {}

    def add_from_msg(self, key: Any, callback: Callable[[Any], Any]) -> None:
        ConvertRegistration.__from_msg_map[_key(key)] = callback

    def add_to_msg(self, key: Any, callback: Callable[[Any], Any]) -> None:
        ConvertRegistration.__to_msg_map[_key(key)] = callback

    def add_convert(self, key: tuple[Any, Any], callback: Callable[[Any], Any]) -> None:
        ConvertRegistration.__convert_map[(_key(key[0]), _key(key[1]))] = callback

    def get_from_msg(self, key: Any) -> Callable[[Any], Any]:
        found = ConvertRegistration.__from_msg_map.get(_key(key))
        if found is None:
            raise TypeException(f"Type {_key(key)} if not loaded or supported")
        return found

    def get_to_msg(self, key: Any) -> Callable[[Any], Any]:
        found = ConvertRegistration.__to_msg_map.get(_key(key))
        if found is None:
            raise TypeException(f"Type {_key(key)} if not loaded or supported")
        return found

    def get_convert(self, key: tuple[Any, Any]) -> Callable[[Any], Any]:
        found = ConvertRegistration.__convert_map.get((_key(key[0]), _key(key[1])))
        if found is None:
            raise TypeException(f"Type {_key(key[0])} if not loaded or supported")
        return found


def convert(a: Any, b_type: Any) -> Any:
    """``a`` as a ``b_type``: the same type is a copy; else a registered conversion, or through a message."""
    if _key(type(a)) == _key(b_type):
        import copy

        return copy.deepcopy(a)
    registration = ConvertRegistration()
    try:
        return registration.get_convert((type(a), b_type))(a)
    except TypeException:
        return registration.get_from_msg(b_type)(registration.get_to_msg(type(a))(a))


class BufferInterface:
    """What every tf2 buffer offers; ``transform`` moves a stamped message into another frame."""

    def __init__(self) -> None:
        self.registration = TransformRegistration()

    def transform(self, object_stamped: Any, target_frame: str, timeout: Any = None, new_type: Any = None) -> Any:
        do_transform = self.registration.get(type(object_stamped))
        res = do_transform(object_stamped, self.lookup_transform(target_frame, object_stamped.header.frame_id,
                                                                 object_stamped.header.stamp, timeout))
        return res if new_type is None else convert(res, new_type)

    def transform_full(self, object_stamped: Any, target_frame: str, target_time: Any, fixed_frame: str,
                       timeout: Any = None, new_type: Any = None) -> Any:
        do_transform = self.registration.get(type(object_stamped))
        res = do_transform(object_stamped, self.lookup_transform_full(
            target_frame, target_time, object_stamped.header.frame_id, object_stamped.header.stamp, fixed_frame,
            timeout))
        return res if new_type is None else convert(res, new_type)

    def lookup_transform(self, target_frame: str, source_frame: str, time: Any, timeout: Any = None) -> Any:
        raise NotImplementedException("lookup_transform is the buffer's")

    def lookup_transform_full(self, target_frame: str, target_time: Any, source_frame: str, source_time: Any,
                              fixed_frame: str, timeout: Any = None) -> Any:
        raise NotImplementedException("lookup_transform_full is the buffer's")

    def can_transform(self, target_frame: str, source_frame: str, time: Any, timeout: Any = None) -> Any:
        raise NotImplementedException("can_transform is the buffer's")

    def can_transform_full(self, target_frame: str, target_time: Any, source_frame: str, source_time: Any,
                           fixed_frame: str, timeout: Any = None) -> Any:
        raise NotImplementedException("can_transform_full is the buffer's")


__all__ = ["BufferInterface", "ConvertRegistration", "NotImplementedException", "TransformRegistration",
           "TypeException", "convert"]
