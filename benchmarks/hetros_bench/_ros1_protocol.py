"""What the ROS 1 benchmark's senders and echoes agree on, hetros's nodes and rospy's alike.

Standard library only: ``_rospy_peer`` runs it under Debian's interpreter (as a module
beside the script), ``_ros1_nodes`` and ``ros1`` import it from the package. A message is
a std_msgs/UInt8MultiArray whose first 16 bytes are the sender's ``monotonic_ns`` stamp
and a sequence number: the sender's ``tag`` in its top 32 bits (0 when one sender is
alone), a count or PROBE or STOP in the low bits. Replies to tag t go to
``reply_topic(t)``. A sender given ``turns`` (two FIFOs) waits for a byte on the first
before each block of exchanges and writes one to the second after it.
"""

from __future__ import annotations

import json
import os
import struct
from typing import Any

PREFIX = struct.Struct("<qq")
TAG_SHIFT = 32
COUNT = (1 << TAG_SHIFT) - 1
PROBE = COUNT
STOP = COUNT - 1


def reply_topic(tag: int) -> str:
    return "/bench_recv" if tag == 0 else f"/bench_recv{tag}"


def measured(count: int, warmup: int, block: int) -> bool:
    """Whether exchange ``count`` is measured: past the warm-up, not the first of a block
    (the receiver then wakes from the other sender's block)."""
    return count >= warmup and not (block and count % block == 0)


def write_result(path: str, result: dict[str, Any]) -> None:
    """The result file, replaced whole: the bench may read it while a serving echo rewrites it."""
    with open(path + ".part", "w") as out:
        json.dump(result, out)
    os.replace(path + ".part", path)


def open_turns(turns: list[str] | None) -> tuple[int | None, int | None]:
    """The FIFOs a sender takes turns by (None, None when alone); says it is ready on the second."""
    if not turns:
        return None, None
    done = os.open(turns[1], os.O_WRONLY)
    os.write(done, b"r")
    return os.open(turns[0], os.O_RDONLY), done
