"""ROS name resolution, shared by the project file's expansion and the nodes' code at run time."""

from __future__ import annotations

from collections.abc import Mapping


def join_namespace(outer: str, inner: str) -> str:
    """``inner`` nested in ``outer`` (an absolute ``inner`` stands alone); always absolute, no trailing /."""
    if inner.startswith("/"):
        joined = inner
    else:
        joined = f"{outer.rstrip('/')}/{inner}" if inner else outer
    joined = "/" + joined.strip("/")
    return joined if joined != "/" else ""


def resolve_name(name: str, namespace: str, node: str, remap: Mapping[str, str] | None = None) -> str:
    """ROS's resolution of a topic, service or action name, then the node's remaps: ``chatter`` ->
    ``<namespace>/chatter``, ``~/x`` -> ``<namespace>/<node>/x``, ``/x`` -> ``/x``."""
    if name.startswith("/"):
        resolved = name
    elif name == "~" or name.startswith("~/"):
        resolved = f"{namespace}/{node}{name[1:]}"
    else:
        resolved = f"{namespace}/{name}"
    return remap.get(resolved, resolved) if remap else resolved
