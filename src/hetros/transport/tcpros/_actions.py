"""hetros' action types as ROS 1's actionlib knows them.

actionlib carries an action ``pkg/Name`` on five topics: ``goal`` (``NameActionGoal``:
header, ``actionlib_msgs/GoalID``, the goal), ``cancel`` (a ``GoalID``), ``status``
(``actionlib_msgs/GoalStatusArray``), ``feedback`` and ``result`` (``NameActionFeedback`` /
``NameActionResult``: header, ``GoalStatus``, the feedback or result). The wrappers come from
rosbags' ROS 1 store when it has them (``actionlib/TwoInts``, ``actionlib/Test``), else they
are made the way ROS 1's genaction makes them, from hetros' goal, result and feedback; the
md5sums then follow from the definitions as ROS 1 computes them.
"""

from __future__ import annotations

import time
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from ..._errors import SerializationError, UnknownTypeError
from ...msg import TypeRegistry, normalize_typename
from ._types import Payload, Ros1Type, ros1_name

PARTS = ("Goal", "Result", "Feedback")
# actionlib_msgs/GoalStatus
PENDING, ACTIVE, PREEMPTED, SUCCEEDED, ABORTED, REJECTED, PREEMPTING, RECALLING, RECALLED, LOST = range(10)
TERMINAL = frozenset((PREEMPTED, SUCCEEDED, ABORTED, REJECTED, RECALLED, LOST))


class Ros1Native:
    """A ROS 1 type whose messages stay rosbags objects of the ROS 1 store (actionlib's wrappers)."""

    def __init__(self, store: Typestore, typename: str) -> None:
        self.typename = typename
        self.name = ros1_name(typename)
        self.definition, self.md5 = store.generate_msgdef(typename, ros_version=1)
        self.cls: Any = store.types[typename]
        self._store = store

    def serialize(self, message: Any) -> Payload:
        try:
            return self._store.serialize_ros1(message, self.typename)
        except (ValueError, TypeError, OverflowError, AttributeError) as exc:
            raise SerializationError(f"cannot serialize {self.name} for ROS 1: {exc}") from exc

    def serialize_parts(self, message: Any) -> list[Payload]:
        return [self.serialize(message)]

    def deserialize(self, data: bytes | memoryview) -> Any:
        try:
            return self._store.deserialize_ros1(data, self.typename)
        except Exception as exc:  # rosbags raises several kinds for bad bytes
            raise SerializationError(f"{len(data)} bytes do not decode as ROS 1 {self.name}: {exc}") from exc


class Ros1ActionType:
    """One hetros action as actionlib topics: the wrapper types and the goal/result/feedback converters."""

    def __init__(self, types: TypeRegistry, name: str) -> None:
        action = types.get_action(name)
        self.typename = action.name
        package, _kind, short = normalize_typename(action.name, "action").split("/")
        self.name = f"{package}/{short}"
        store = get_typestore(Stores.ROS1_NOETIC)
        ros1 = {part: f"{package}/msg/{short}{part}" for part in PARTS}
        definitions: dict[str, Any] = {}
        for part in PARTS:
            inner = store.fielddefs.get(ros1[part]) or types.fielddefs[f"{action.name}_{part}"]
            definitions.setdefault(ros1[part], inner)
            # under hetros' name too, so the field-by-name converters of Ros1Type apply unchanged
            definitions[f"{action.name}_{part}"] = inner
        header = ("header", (Nodetype.NAME, "std_msgs/msg/Header"))
        status = ("status", (Nodetype.NAME, "actionlib_msgs/msg/GoalStatus"))
        wrappers = {
            f"{package}/msg/{short}ActionGoal": [header, ("goal_id", (Nodetype.NAME, "actionlib_msgs/msg/GoalID")),
                                                 ("goal", (Nodetype.NAME, ros1["Goal"]))],
            f"{package}/msg/{short}ActionResult": [header, status, ("result", (Nodetype.NAME, ros1["Result"]))],
            f"{package}/msg/{short}ActionFeedback": [header, status, ("feedback", (Nodetype.NAME, ros1["Feedback"]))],
        }
        for wrapper, fields in wrappers.items():
            if wrapper not in store.fielddefs:
                definitions[wrapper] = ([], fields)
        try:
            store.register({k: v for k, v in definitions.items() if k not in store.fielddefs})
        except Exception as exc:  # rosbags refuses definitions that name unknown ROS 1 types
            raise UnknownTypeError(f"action {action.name} cannot be mapped to ROS 1 actionlib: {exc}") from None
        self.goal, self.result, self.feedback = (Ros1Native(store, w) for w in wrappers)
        self.status = Ros1Native(store, "actionlib_msgs/msg/GoalStatusArray")
        self.cancel = Ros1Native(store, "actionlib_msgs/msg/GoalID")
        self.inner = {part: Ros1Type(types, f"{action.name}_{part}", store) for part in PARTS}
        self._store = store

    def ros1(self, typename: str) -> Any:
        """A ROS 1 message class of this action's store (``std_msgs/msg/Header``, ``actionlib_msgs/msg/GoalID``)."""
        return self._store.types[typename]

    def stamp(self, seconds: float | None = None) -> Any:
        now = time.time_ns() if seconds is None else int(seconds * 1e9)
        return self.ros1("builtin_interfaces/msg/Time")(sec=now // 1_000_000_000, nanosec=now % 1_000_000_000)

    def header(self) -> Any:
        return self.ros1("std_msgs/msg/Header")(seq=0, stamp=self.stamp(), frame_id="")

    def goal_id(self, goal_id: str, stamp: Any = None) -> Any:
        return self.ros1("actionlib_msgs/msg/GoalID")(stamp=stamp if stamp is not None else self.stamp(), id=goal_id)

    def goal_status(self, goal_id: Any, status: int, text: str = "") -> Any:
        return self.ros1("actionlib_msgs/msg/GoalStatus")(goal_id=goal_id, status=status, text=text)
