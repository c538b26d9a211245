"""rclpy.qos: QoS profiles as rclpy spells them, turned into hetros's QoS (which the project file's overrides)."""

from __future__ import annotations

import enum
from typing import Any

from ..._qos import DELIVERY_POLICIES, QoS
from ..._qos import delivery_conflicts as conflicts_of


class HistoryPolicy(enum.IntEnum):
    SYSTEM_DEFAULT = 0
    KEEP_LAST = 1
    KEEP_ALL = 2
    UNKNOWN = 3


class ReliabilityPolicy(enum.IntEnum):
    SYSTEM_DEFAULT = 0
    RELIABLE = 1
    BEST_EFFORT = 2
    UNKNOWN = 3
    BEST_AVAILABLE = 4


class DurabilityPolicy(enum.IntEnum):
    SYSTEM_DEFAULT = 0
    TRANSIENT_LOCAL = 1
    VOLATILE = 2
    UNKNOWN = 3
    BEST_AVAILABLE = 4


class LivelinessPolicy(enum.IntEnum):
    SYSTEM_DEFAULT = 0
    AUTOMATIC = 1
    MANUAL_BY_TOPIC = 3
    UNKNOWN = 4
    BEST_AVAILABLE = 5


class QoSPolicyKind(enum.IntEnum):
    """The policies ROS 2 names in incompatible-QoS events (rmw's values)."""

    INVALID = 1 << 0
    DURABILITY = 1 << 1
    DEADLINE = 1 << 2
    LIVELINESS = 1 << 3
    RELIABILITY = 1 << 4
    HISTORY = 1 << 5
    LIFESPAN = 1 << 6
    DEPTH = 1 << 7
    LIVELINESS_LEASE_DURATION = 1 << 8
    AVOID_ROS_NAMESPACE_CONVENTIONS = 1 << 9


def qos_policy_name_from_kind(policy_kind: QoSPolicyKind | int) -> str:
    return QoSPolicyKind(policy_kind).name


QoSHistoryPolicy = HistoryPolicy
QoSReliabilityPolicy = ReliabilityPolicy
QoSDurabilityPolicy = DurabilityPolicy
QoSLivelinessPolicy = LivelinessPolicy


class QoSProfile:
    """rclpy's QoSProfile: keep_last depth 10, reliable, volatile unless told otherwise. It remembers which
    delivery policies the code chose (given, or set after), so that only those are held against the
    project file's QoS of the topic (:func:`delivery_conflicts`)."""

    _DELIVERY = DELIVERY_POLICIES

    def __init__(self, *, history: HistoryPolicy | None = None, depth: int | None = None,
                 reliability: ReliabilityPolicy | None = None, durability: DurabilityPolicy | None = None,
                 liveliness: LivelinessPolicy = LivelinessPolicy.SYSTEM_DEFAULT, deadline: Any = None,
                 lifespan: Any = None, liveliness_lease_duration: Any = None, **_ignored: Any) -> None:
        chosen = {name for name, value in (("history", history), ("reliability", reliability),
                                           ("durability", durability)) if value is not None}
        self.history = HistoryPolicy(HistoryPolicy.KEEP_LAST if history is None else history)
        self.depth = 10 if depth is None else int(depth)
        self.reliability = ReliabilityPolicy(ReliabilityPolicy.RELIABLE if reliability is None else reliability)
        self.durability = DurabilityPolicy(DurabilityPolicy.VOLATILE if durability is None else durability)
        self.liveliness = LivelinessPolicy(liveliness)
        # rclpy Durations (zero or absent: infinite, ROS 2's default)
        self.deadline, self.lifespan = deadline, lifespan
        self.liveliness_lease_duration = liveliness_lease_duration
        self.chosen = chosen

    def __setattr__(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)
        if name in self._DELIVERY and "chosen" in self.__dict__:
            self.chosen.add(name)

    def __repr__(self) -> str:
        return (f"QoSProfile(history={self.history.name}, depth={self.depth}, reliability={self.reliability.name}, "
                f"durability={self.durability.name})")


def delivery_conflicts(profile: QoSProfile | int, declared: QoS, subscription: bool = False) -> list[str]:
    """The delivery policies the code chose (:class:`QoSProfile` remembers them; a bare depth chooses
    none) that the topic's QoS from the project file contradicts (:func:`hetros._qos.delivery_conflicts`)."""
    if isinstance(profile, int):
        return []
    asked = to_hetros(profile)
    assert asked is not None
    return conflicts_of({name: getattr(asked, name) for name in profile.chosen}, declared, subscription)


def to_hetros(profile: QoSProfile | int | None) -> QoS | None:
    """What the code asked for, as hetros's QoS: a bare depth means keep_last of it, as in rclpy."""
    if profile is None:
        return None
    if isinstance(profile, int):
        profile = QoSProfile(depth=profile)
    return QoS(reliability="best_effort" if profile.reliability == ReliabilityPolicy.BEST_EFFORT else "reliable",
               history="keep_all" if profile.history == HistoryPolicy.KEEP_ALL else "keep_last",
               depth=max(profile.depth, 1),
               durability="transient_local" if profile.durability == DurabilityPolicy.TRANSIENT_LOCAL
               else "volatile",
               deadline=_seconds(getattr(profile, "deadline", None)),
               lifespan=_seconds(getattr(profile, "lifespan", None)),
               liveliness="manual_by_topic" if profile.liveliness == LivelinessPolicy.MANUAL_BY_TOPIC else "automatic",
               lease_duration=_seconds(getattr(profile, "liveliness_lease_duration", None)))


def from_hetros(qos: QoS) -> QoSProfile:
    """hetros's QoS as rclpy's profile (what graph queries report of an endpoint)."""
    return QoSProfile(depth=qos.depth,
                      history=HistoryPolicy.KEEP_ALL if qos.history == "keep_all" else HistoryPolicy.KEEP_LAST,
                      reliability=ReliabilityPolicy.BEST_EFFORT if qos.reliability == "best_effort"
                      else ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if qos.durability == "transient_local"
                      else DurabilityPolicy.VOLATILE)


def _seconds(duration: Any) -> float | None:
    """An rclpy Duration as hetros's seconds; zero, absent or rclpy's infinite as None (no bound)."""
    nanoseconds = getattr(duration, "nanoseconds", None)
    if nanoseconds is None or nanoseconds <= 0 or nanoseconds >= 2**63 - 1:
        return None
    return float(nanoseconds) / 1e9


qos_profile_system_default = QoSProfile()
qos_profile_services_default = QoSProfile()
qos_profile_parameters = QoSProfile(depth=1000)
qos_profile_parameter_events = QoSProfile(depth=1000)
qos_profile_sensor_data = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
qos_profile_action_status_default = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class QoSPresetProfiles(enum.Enum):
    SYSTEM_DEFAULT = qos_profile_system_default
    SENSOR_DATA = qos_profile_sensor_data
    SERVICES_DEFAULT = qos_profile_services_default
    PARAMETERS = qos_profile_parameters
    PARAMETER_EVENTS = qos_profile_parameter_events
    ACTION_STATUS_DEFAULT = qos_profile_action_status_default

    @classmethod
    def get_from_short_key(cls, name: str) -> QoSProfile:
        profile: QoSProfile = cls[name.upper()].value
        return profile
