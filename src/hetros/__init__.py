"""hetros: ROS-compatible Python nodes, mapped by one project file onto threads,
processes pinned to cores, hardware or other machines, with a statically planned
data distribution service underneath."""

from typing import TYPE_CHECKING, Any

from ._signals import honour_stop_signals, is_command_line

if is_command_line():  # before the imports below: they take most of a second
    honour_stop_signals()

from ._errors import (
    ActionError,
    ActionTimeoutError,
    AdviseError,
    CheckError,
    DefinitionError,
    Error,
    FieldValueError,
    GoalRejectedError,
    HardwareError,
    InputFileError,
    InspectError,
    LaunchError,
    LaunchFileError,
    MachineError,
    MessageError,
    MissingFieldError,
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
from ._qos import QoS
from .msg import Message
from .runtime import (
    Client,
    Clock,
    DeadlineMissedStatus,
    Duration,
    IncompatibleQosStatus,
    LivelinessChangedStatus,
    LivelinessLostStatus,
    MatchedStatus,
    MessageLostStatus,
    Node,
    Publisher,
    Service,
    Subscription,
    Time,
    Timer,
)

if TYPE_CHECKING:
    from .runtime import ActionClient, ActionServer, ClientGoalHandle, GoalStatus, ServerGoalHandle

# actions are loaded on first use: a worker whose nodes have none does not pay for them
_ACTIONS = frozenset({"ActionClient", "ActionServer", "ClientGoalHandle", "GoalStatus", "ServerGoalHandle"})


def __getattr__(name: str) -> Any:
    if name not in _ACTIONS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from . import runtime

    return getattr(runtime, name)


__version__ = "0.1.0"

__all__ = [
    "ActionClient",
    "ActionError",
    "ActionServer",
    "ActionTimeoutError",
    "AdviseError",
    "CheckError",
    "Client",
    "ClientGoalHandle",
    "Clock",
    "DeadlineMissedStatus",
    "DefinitionError",
    "Duration",
    "Error",
    "FieldValueError",
    "GoalRejectedError",
    "GoalStatus",
    "HardwareError",
    "IncompatibleQosStatus",
    "InputFileError",
    "InspectError",
    "LaunchError",
    "LaunchFileError",
    "LivelinessChangedStatus",
    "LivelinessLostStatus",
    "MachineError",
    "MatchedStatus",
    "Message",
    "MessageError",
    "MessageLostStatus",
    "MissingFieldError",
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
    "ServerGoalHandle",
    "Service",
    "ServiceTimeoutError",
    "ShutdownError",
    "Subscription",
    "TakeTimeoutError",
    "Time",
    "Timer",
    "TopicTypeError",
    "TransportError",
    "UndeclaredEndpointError",
    "UnknownTypeError",
    "__version__",
]
