"""rclpy.event_handler: QoS event callbacks, on hetros's QoS, matched and liveliness events.

``create_subscription(..., event_callbacks=SubscriptionEventCallbacks(deadline=..., liveliness=...))``
and ``create_publisher(..., event_callbacks=PublisherEventCallbacks(deadline=...))`` run the callbacks
in the node's executor with ROS 2's status fields; ``message_lost`` counts what keep_last overwrote, a
lifespan expired or best_effort dropped before the subscription took it. ``incompatible_qos`` fires when
two endpoints of one process ask, on a topic the project file gives no QoS, for QoS that does not match
(``hetros check`` refuses such a pair where the project declares it): neither counts the other as
matched and the subscription hears nothing from that publisher, as in ROS 2; without a callback, rclpy's
warning is logged. ``matched`` reports subscriptions and publishers that come and go (the plan's
endpoints in other processes count from the start; see ``hetros.MatchedStatus``); a publisher's
``liveliness`` counts the leases a manual_by_topic publisher let pass. The event hetros does not raise
(``incompatible_type``: hetros check refuses two types on one topic) is refused with a line naming it,
never ignored: ``UnsupportedEventTypeError``, as rclpy raises for a middleware without the event.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

from ..._errors import NodeError
from ...runtime import (
    DeadlineMissedStatus,
    IncompatibleQosStatus,
    LivelinessChangedStatus,
    LivelinessLostStatus,
    MatchedStatus,
    MessageLostStatus,
)
from .logging import RcutilsLogger
from .qos import QoSPolicyKind, qos_policy_name_from_kind

QoSRequestedDeadlineMissedInfo = DeadlineMissedStatus
QoSOfferedDeadlineMissedInfo = DeadlineMissedStatus
QoSLivelinessChangedInfo = LivelinessChangedStatus
QoSLivelinessLostInfo = LivelinessLostStatus
QoSMessageLostInfo = MessageLostStatus
QoSPublisherMatchedInfo = MatchedStatus
QoSSubscriptionMatchedInfo = MatchedStatus


class rmw_qos_policy_kind_t(enum.IntEnum):
    """The policy an incompatible-QoS event names; prints as rclpy's binding prints it."""

    RMW_QOS_POLICY_INVALID = QoSPolicyKind.INVALID
    RMW_QOS_POLICY_DURABILITY = QoSPolicyKind.DURABILITY
    RMW_QOS_POLICY_DEADLINE = QoSPolicyKind.DEADLINE
    RMW_QOS_POLICY_LIVELINESS = QoSPolicyKind.LIVELINESS
    RMW_QOS_POLICY_RELIABILITY = QoSPolicyKind.RELIABILITY
    RMW_QOS_POLICY_HISTORY = QoSPolicyKind.HISTORY
    RMW_QOS_POLICY_LIFESPAN = QoSPolicyKind.LIFESPAN
    RMW_QOS_POLICY_DEPTH = QoSPolicyKind.DEPTH
    RMW_QOS_POLICY_LIVELINESS_LEASE_DURATION = QoSPolicyKind.LIVELINESS_LEASE_DURATION

    def __str__(self) -> str:
        return f"rmw_qos_policy_kind_t.{self.name}"

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


_POLICY_KINDS = {"reliability": rmw_qos_policy_kind_t.RMW_QOS_POLICY_RELIABILITY,
                 "durability": rmw_qos_policy_kind_t.RMW_QOS_POLICY_DURABILITY,
                 "deadline": rmw_qos_policy_kind_t.RMW_QOS_POLICY_DEADLINE,
                 "liveliness": rmw_qos_policy_kind_t.RMW_QOS_POLICY_LIVELINESS,
                 "lease_duration": rmw_qos_policy_kind_t.RMW_QOS_POLICY_LIVELINESS_LEASE_DURATION}


@dataclass(frozen=True)
class QoSRequestedIncompatibleQoSInfo:
    total_count: int
    total_count_change: int
    last_policy_kind: rmw_qos_policy_kind_t


QoSOfferedIncompatibleQoSInfo = QoSRequestedIncompatibleQoSInfo


@dataclass
class SubscriptionEventCallbacks:
    deadline: Callable[[DeadlineMissedStatus], Any] | None = None
    incompatible_qos: Callable[[Any], Any] | None = None
    liveliness: Callable[[LivelinessChangedStatus], Any] | None = None
    message_lost: Callable[[Any], Any] | None = None
    incompatible_type: Callable[[Any], Any] | None = None
    matched: Callable[[Any], Any] | None = None
    use_default_callbacks: bool = True


@dataclass
class PublisherEventCallbacks:
    deadline: Callable[[DeadlineMissedStatus], Any] | None = None
    liveliness: Callable[[Any], Any] | None = None
    incompatible_qos: Callable[[Any], Any] | None = None
    incompatible_type: Callable[[Any], Any] | None = None
    matched: Callable[[Any], Any] | None = None
    use_default_callbacks: bool = True


class UnsupportedEventTypeError(NodeError):
    """An event this middleware does not raise (rclpy raises it for an RMW without the event)."""


_SUPPORTED = {"deadline", "liveliness", "incompatible_qos", "message_lost", "matched", "use_default_callbacks"}


def supported(callbacks: SubscriptionEventCallbacks | PublisherEventCallbacks, where: str) -> None:
    """Refuse the events hetros never raises, naming them (a callback that silently never runs would be
    a lie)."""
    unsupported = [f.name for f in fields(callbacks) if getattr(callbacks, f.name) is not None and
                   f.name not in _SUPPORTED]
    if unsupported:
        raise UnsupportedEventTypeError(f"{where}: event_callbacks {', '.join(unsupported)} are events hetros does "
                                        "not raise; remove them (deadline, liveliness, message_lost, matched and "
                                        "incompatible_qos are supported)")


def incompatible_qos_handler(callbacks: SubscriptionEventCallbacks | PublisherEventCallbacks | None,
                             logger: RcutilsLogger, topic: str, *,
                             publisher: bool) -> Callable[[IncompatibleQosStatus], None] | None:
    """What runs on an incompatible-QoS event of a publisher (or a subscription): the code's callback, else
    (``use_default_callbacks``, as when no callbacks are given) rclpy's warning for that side."""
    chosen = callbacks.incompatible_qos if callbacks is not None else None
    if chosen is None and (callbacks is None or callbacks.use_default_callbacks):
        if publisher:
            told = (f"New subscription discovered on topic '{topic}', requesting incompatible QoS. "
                    "No messages will be sent to it. Last incompatible policy: ")
        else:
            told = (f"New publisher discovered on topic '{topic}', offering incompatible QoS. "
                    "No messages will be received from it. Last incompatible policy: ")

        def chosen(info: QoSRequestedIncompatibleQoSInfo) -> None:
            logger.warn(told + qos_policy_name_from_kind(info.last_policy_kind))
    if chosen is None:
        return None
    run = chosen

    def report(status: IncompatibleQosStatus) -> None:
        run(QoSRequestedIncompatibleQoSInfo(status.total_count, status.total_count_change,
                                            _POLICY_KINDS[status.last_policy_kind]))
    return report


__all__ = [
    "PublisherEventCallbacks",
    "QoSLivelinessChangedInfo",
    "QoSLivelinessLostInfo",
    "QoSMessageLostInfo",
    "QoSOfferedDeadlineMissedInfo",
    "QoSOfferedIncompatibleQoSInfo",
    "QoSPublisherMatchedInfo",
    "QoSRequestedDeadlineMissedInfo",
    "QoSRequestedIncompatibleQoSInfo",
    "QoSSubscriptionMatchedInfo",
    "SubscriptionEventCallbacks",
    "UnsupportedEventTypeError",
    "rmw_qos_policy_kind_t",
]
