"""rclpy.qos_event (rclpy before Jazzy): the QoS event callbacks, as ``rclpy.event_handler`` has them."""

from .event_handler import (
    PublisherEventCallbacks,
    QoSLivelinessChangedInfo,
    QoSOfferedDeadlineMissedInfo,
    QoSRequestedDeadlineMissedInfo,
    SubscriptionEventCallbacks,
)

__all__ = [
    "PublisherEventCallbacks",
    "QoSLivelinessChangedInfo",
    "QoSOfferedDeadlineMissedInfo",
    "QoSRequestedDeadlineMissedInfo",
    "SubscriptionEventCallbacks",
]
