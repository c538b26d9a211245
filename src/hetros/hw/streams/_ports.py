"""The port contract nodes and builders share: how a topic or a service names the stream ports of a
hardware node and of the target's top module (``/camera/image`` -> ``camera_image``)."""

from __future__ import annotations

import re


def service_ports(service: str) -> tuple[str, str]:
    """A hardware server's two ports for ``service``: requests in, responses out, one for each, in order."""
    return f"{port_part(service)}_request", f"{port_part(service)}_response"


def port_part(topic: str) -> str:
    """``/camera/image`` -> ``camera_image``: the part of a port name that names the topic."""
    return re.sub(r"[^A-Za-z0-9_]", "_", topic.strip("/"))
