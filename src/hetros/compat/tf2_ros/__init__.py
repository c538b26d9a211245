"""tf2_ros for rclpy and rospy nodes, on hetros's transform tree (``hetros.compat.tf2_py``): ``Buffer``,
``TransformListener``, ``TransformBroadcaster``, ``StaticTransformBroadcaster`` and tf2's exceptions."""

from ..tf2_py import (
    ConnectivityException,
    ExtrapolationException,
    InvalidArgumentException,
    LookupException,
    TimeoutException,
    TransformException,
)
from .buffer import Buffer
from .buffer_interface import (
    BufferInterface,
    ConvertRegistration,
    NotImplementedException,
    TransformRegistration,
    TypeException,
    convert,
)
from .static_transform_broadcaster import StaticTransformBroadcaster
from .transform_broadcaster import TransformBroadcaster
from .transform_listener import TransformListener

__all__ = [
    "Buffer",
    "BufferInterface",
    "ConnectivityException",
    "ConvertRegistration",
    "ExtrapolationException",
    "InvalidArgumentException",
    "LookupException",
    "NotImplementedException",
    "StaticTransformBroadcaster",
    "TimeoutException",
    "TransformBroadcaster",
    "TransformException",
    "TransformListener",
    "TransformRegistration",
    "TypeException",
    "convert",
]
