"""hetros: ROS-compatible Python nodes, mapped by one project file onto threads,
processes pinned to cores, hardware or other machines, with a statically planned
data distribution service underneath."""

from ._errors import (
    CheckError,
    DefinitionError,
    Error,
    FieldValueError,
    LaunchError,
    MessageError,
    NodeError,
    ParameterError,
    ProjectError,
    ProtocolError,
    PublishTimeoutError,
    ReadOnlyMessageError,
    SerializationError,
    ServiceTimeoutError,
    ShutdownError,
    TakeTimeoutError,
    TopicTypeError,
    TransportError,
    UndeclaredEndpointError,
    UnknownTypeError,
)
from .msg import Message
from .runtime import Client, Node, Publisher, Service, Subscription, Timer
from .transport import QoS

__version__ = "0.1.0"

__all__ = [
    "CheckError",
    "Client",
    "DefinitionError",
    "Error",
    "FieldValueError",
    "LaunchError",
    "Message",
    "MessageError",
    "Node",
    "NodeError",
    "ParameterError",
    "ProjectError",
    "ProtocolError",
    "PublishTimeoutError",
    "Publisher",
    "QoS",
    "ReadOnlyMessageError",
    "SerializationError",
    "Service",
    "ServiceTimeoutError",
    "ShutdownError",
    "Subscription",
    "TakeTimeoutError",
    "Timer",
    "TopicTypeError",
    "TransportError",
    "UndeclaredEndpointError",
    "UnknownTypeError",
    "__version__",
]
