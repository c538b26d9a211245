"""ROS 2's rules for node, topic and service names (rmw's validate_full_topic_name and
validate_node_name), so a name hetros accepts is one a ROS graph accepts too."""

from __future__ import annotations

import re

MAX_NAME = 255
_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# project, target and host names become parts of file, shared-memory and DDS topic names
MAX_PLAIN_NAME = 63
_PLAIN = re.compile(r"[A-Za-z][A-Za-z0-9_-]*\Z")
PLAIN_NAME_RULE = (f"an ASCII letter, then ASCII letters, digits, '_' or '-', at most {MAX_PLAIN_NAME} "
                   "characters in all")


def topic_name_problem(name: str) -> str | None:
    """Why ``name`` is not a fully qualified ROS 2 topic or service name, or None when it is."""
    if not name:
        return "a topic or service name must not be empty"
    if len(name) > MAX_NAME:
        return f"is {len(name)} characters long; ROS names have at most {MAX_NAME}"
    if not name.startswith("/"):
        return f"names must be absolute, like '/{name}'"
    if name != "/" and name.endswith("/"):
        return "must not end with '/'"
    if "//" in name:
        return "must not contain '//' (an empty name part)"
    for token in name[1:].split("/"):
        if not _TOKEN.match(token):
            bad = next((c for c in token if not (c.isascii() and (c.isalnum() or c == "_"))), None)
            if bad is not None:
                return (f"part {token!r} contains {bad!r}; ROS names use only ASCII letters, digits, "
                        "'_' and '/'")
            return f"part {token!r} starts with a digit; each part of a ROS name starts with a letter or '_'"
    return None


def node_name_problem(name: str) -> str | None:
    """Why ``name`` is not a valid ROS 2 node name, or None when it is."""
    if not name:
        return "a node name must not be empty"
    if len(name) > MAX_NAME:
        return f"is {len(name)} characters long; ROS names have at most {MAX_NAME}"
    if not _TOKEN.match(name):
        return (f"node name {name!r} is not a ROS name: node names use only ASCII letters, digits and '_', "
                "and start with a letter or '_'")
    return None


def plain_name_problem(what: str, name: object) -> str | None:
    """Why ``name`` cannot name a project, target or host (``what``), or None when it can.

    These names end up in file names, iceoryx2 service names and DDS topic names
    (``hetros/<project>/<host>/<channel>``), so one rule keeps them safe in all three.
    """
    if isinstance(name, str) and len(name) <= MAX_PLAIN_NAME and _PLAIN.match(name):
        return None
    return f"{what} name must be {PLAIN_NAME_RULE}, not {name!r}"
