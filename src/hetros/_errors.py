"""The error tree of hetros.

Every failure hetros reports derives from :class:`Error`, so a caller can catch
one root and still tell the kinds apart::

    Error
    ├── MessageError           .msg/.srv/.action definitions and types
    │   ├── DefinitionError    a malformed definition file (file:line)
    │   ├── UnknownTypeError   a type name nobody defines
    │   ├── SerializationError bytes that do not decode as the type says (offset)
    │   ├── FieldValueError    a field holds a value its type cannot carry (field, type, value)
    │   ├── ReadOnlyMessageError  writing to a message that was handed over
    │   └── MissingFieldError  a ROS 1 field ROS 2's layout dropped (header.seq), asked by rospy code
    ├── ProjectError           the project file (YAML path)
    │   ├── CheckError         `hetros check` found problems (carries all of them)
    │   └── LaunchFileError    a ROS launch file asks what its description cannot give (file:line)
    ├── TransportError         moving messages
    │   ├── ProtocolError         a peer broke its protocol (TCPROS header, frame; offset)
    │   ├── PublishTimeoutError   back-pressure outlasted the timeout
    │   └── TopicTypeError        a message of the wrong type for the topic
    ├── NodeError              the node API used wrongly
    │   ├── UndeclaredEndpointError  an endpoint the project file does not declare
    │   ├── ParameterError     a parameter missing or of the wrong type
    │   ├── TakeTimeoutError   sub.take(timeout=) saw no message in time
    │   ├── ServiceTimeoutError   a service call got no reply in time
    │   └── ActionError        an action goal that cannot go on (its cause named)
    │       ├── GoalRejectedError   the server rejected the goal
    │       └── ActionTimeoutError  no answer, goal or result in time
    ├── HardwareError          an fpga target's topic network cannot be built as asked
    ├── ShutdownError          a blocking call interrupted by graph shutdown
    ├── LaunchError            starting or supervising the graph
    ├── MachineError           the machine around a launch: a private folder squatted or foreign,
    │                          shared memory full (named, with the fix)
    ├── InputFileError         a file a user named is not what it must be: a FIFO, a device, a
    │                          folder, too large, too deeply nested, not text (named, with the fix)
    ├── InspectError           looking inside a running launch (which one, what, refused)
    ├── AdviseError            the mapping advisor: no such chain, a profile of another project or
    │                          machine, a deadline no mapping meets (by how much, and why)
    └── BenchError             a benchmark run gave no samples (hetros_bench; its text goes in the report)
"""

from __future__ import annotations

from collections.abc import Sequence


class Error(Exception):
    """Root of every error hetros raises."""


class MessageError(Error):
    """A message type or definition is wrong."""


class DefinitionError(MessageError):
    """A .msg/.srv/.action file is malformed; the message names file:line."""

    def __init__(self, path: str, line: int, reason: str) -> None:
        self.path = path
        self.line = line
        self.reason = reason
        super().__init__(f"{path}:{line}: {reason}")


class UnknownTypeError(MessageError):
    """A type name that no loaded package defines."""


class SerializationError(MessageError):
    """Bytes that cannot be decoded as the declared type."""


class FieldValueError(MessageError, ValueError):
    """A field holds a value of the wrong type or out of its type's range."""


class ReadOnlyMessageError(MessageError, AttributeError):
    """A delivered (or published) message was written to."""


class MissingFieldError(MessageError, AttributeError):
    """rospy code used a field of a ROS 1 message that hetros's (ROS 2) layout of the type lacks."""


class ProjectError(Error):
    """The project file is invalid; the message names the YAML path."""


class LaunchFileError(ProjectError):
    """A ROS launch file (Python, XML, YAML) asks for what its description cannot give, or for what hetros
    cannot express; the message names the file and line."""


class CheckError(ProjectError):
    """`hetros check` found one or more problems."""

    def __init__(self, problems: Sequence[str]) -> None:
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"{len(self.problems)} problem(s) in the project:\n{lines}")


class TransportError(Error):
    """A transport failed to move a message."""


class ProtocolError(TransportError):
    """A peer sent bytes that break its protocol (a TCPROS header, a frame length); the
    message names the peer and the offset. The connection is dropped, the node goes on."""


class PublishTimeoutError(TransportError):
    """A reliable publisher stayed blocked by a full subscriber FIFO too long."""


class TopicTypeError(TransportError, TypeError):
    """A message of the wrong type was published on a topic."""


class NodeError(Error):
    """The node API was used in a way the project does not allow."""


class UndeclaredEndpointError(NodeError):
    """A node created an endpoint that its project entry does not declare."""


class ParameterError(NodeError):
    """A parameter is missing or has the wrong type."""


class TakeTimeoutError(NodeError, TimeoutError):
    """``sub.take(timeout=...)`` saw no message in time."""


class ServiceTimeoutError(NodeError, TimeoutError):
    """A service call got no reply within its timeout."""


class ActionError(NodeError):
    """An action goal that cannot go on: its server went away, it already ended, the graph stopped."""


class GoalRejectedError(ActionError):
    """The action server rejected the goal."""


class ActionTimeoutError(ActionError, TimeoutError):
    """An action's answer, goal or result did not come in time."""


class HardwareError(Error):
    """An fpga target's topic network, message layout or tool run cannot be done as asked."""


class ShutdownError(Error):
    """A blocking call was interrupted because the graph is shutting down."""


class LaunchError(Error):
    """The launcher could not start or keep the graph running."""


class MachineError(Error):
    """The machine around a launch cannot be used safely as it is: one of this user's private
    folders belongs to someone else or is a link, or shared memory has no room; the message
    names the path and what to do."""


class InputFileError(Error):
    """A file a user or another account can name (a project, record, plan, profile, launch file,
    parameter file, recording) cannot be read as what it must be: it is not a regular file, is
    larger or more deeply nested than such a file can be, or does not decode; the message names
    the file and what to do."""


class InspectError(Error):
    """A look inside a running launch failed: no launch or several, an unknown topic or node, a
    process that did not answer."""


class AdviseError(Error):
    """The mapping advisor cannot give the advice asked: a chain that does not exist, a profile that
    does not fit the project, a deadline no mapping within the limits meets (the message says by how
    much the best misses and which node dominates)."""
