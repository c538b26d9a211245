"""rclpy.event_handler: QoS event callbacks, on hetros's deadline and liveliness events.

``create_subscription(..., event_callbacks=SubscriptionEventCallbacks(deadline=..., liveliness=...))``
and ``create_publisher(..., event_callbacks=PublisherEventCallbacks(deadline=...))`` run the callbacks
in the node's executor with ROS 2's status fields; ``message_lost`` counts what keep_last overwrote, a
lifespan expired or best_effort dropped before the subscription took it. ``incompatible_qos`` never fires
under hetros: ``hetros check`` refuses a project whose publishers and subscribers of a topic cannot talk, so a launch
never has such a pair. ``matched`` reports subscriptions and publishers that come and go (the plan's
endpoints in other processes count from the start; see ``hetros.MatchedStatus``). The events hetros does
not raise (``incompatible_type``, a publisher's ``liveliness``) are refused with a line naming them, never
ignored: ``UnsupportedEventTypeError``, as rclpy raises for a middleware without the event.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

from ..._errors import NodeError
from ...runtime import DeadlineMissedStatus, LivelinessChangedStatus, MatchedStatus, MessageLostStatus

QoSRequestedDeadlineMissedInfo = DeadlineMissedStatus
QoSOfferedDeadlineMissedInfo = DeadlineMissedStatus
QoSLivelinessChangedInfo = LivelinessChangedStatus
QoSMessageLostInfo = MessageLostStatus
QoSPublisherMatchedInfo = MatchedStatus
QoSSubscriptionMatchedInfo = MatchedStatus


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
    a lie); a publisher's liveliness_lost is one of them."""
    unsupported = [f.name for f in fields(callbacks) if getattr(callbacks, f.name) is not None and
                   f.name not in _SUPPORTED]
    if isinstance(callbacks, PublisherEventCallbacks) and callbacks.liveliness is not None:
        unsupported.append("liveliness")
    if unsupported:
        raise UnsupportedEventTypeError(f"{where}: event_callbacks {', '.join(unsupported)} are events hetros does "
                                        "not raise; remove them (deadline, message_lost, matched and a "
                                        "subscription's liveliness are supported)")


__all__ = [
    "PublisherEventCallbacks",
    "QoSLivelinessChangedInfo",
    "QoSMessageLostInfo",
    "QoSOfferedDeadlineMissedInfo",
    "QoSPublisherMatchedInfo",
    "QoSRequestedDeadlineMissedInfo",
    "QoSSubscriptionMatchedInfo",
    "SubscriptionEventCallbacks",
    "UnsupportedEventTypeError",
]
