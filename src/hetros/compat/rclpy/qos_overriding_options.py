"""rclpy.qos_overriding_options: the options a publisher or subscription takes for QoS overrides.

ROS 2 turns them into read-only parameters (``qos_overrides.<topic>.publisher.depth``) that a
parameter file may set at start-up. In hetros the project file's ``topics:`` section is that place,
for every endpoint of a topic at once; the options are accepted, and their callback validates the
QoS the endpoint gets, as rclpy's does (a refusal raises ``InvalidQosOverridesError``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from ..._errors import NodeError
from .qos import QoSPolicyKind


class InvalidQosOverridesError(NodeError):
    pass


@dataclass
class QosCallbackResult:
    successful: bool = False
    reason: str = ""


@dataclass
class QoSOverridingOptions:
    policy_kinds: Iterable[QoSPolicyKind]
    callback: Callable[[Any], QosCallbackResult] | None = None
    entity_id: str | None = None

    @classmethod
    def with_default_policies(cls, *, callback: Callable[[Any], QosCallbackResult] | None = None,
                              entity_id: str | None = None) -> QoSOverridingOptions:
        return cls((QoSPolicyKind.HISTORY, QoSPolicyKind.DEPTH, QoSPolicyKind.RELIABILITY), callback, entity_id)


def validate(options: Any, qos: Any, where: str) -> None:
    """Run the options' callback on the QoS an endpoint is created with."""
    callback = getattr(options, "callback", None)
    if callback is None:
        return
    result = callback(qos)
    if not getattr(result, "successful", False):
        raise InvalidQosOverridesError(f"{where}: the QoS override callback refused {qos}: "
                                       f"{getattr(result, 'reason', '') or 'no reason given'}")


__all__ = ["InvalidQosOverridesError", "QoSOverridingOptions", "QoSPolicyKind", "QosCallbackResult"]
