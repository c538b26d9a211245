"""Same-host, cross-process transport on iceoryx2 shared memory.

Layout, fixed by the static plan (no discovery at run time):

* one iceoryx2 publish-subscribe service per (topic, publishing target), so a
  process never receives through shared memory what it already delivered to
  itself in-process; all publishers of a service live in one process;
* one *wake channel* (an iceoryx2 event service) per subscribing node: every
  reader of the node has an event id on it, and the node's executor is the only
  thing that waits on it (no thread per reader);
* one *back channel* per publishing process, watched by one thread, that wakes
  publishers blocked on a full FIFO and connects late joiners to history;
* a small *credits* file in /dev/shm per service: the sequence number last
  published and, per subscriber slot, the sequence it last took, its pid and
  the wake channel and event id to notify. A reliable keep_all publisher
  computes each subscriber's fill level from it and blocks while a FIFO holds
  ``depth`` messages: back-pressure across processes, with a timeout and with
  crashed subscribers detected by pid.

Nothing on a reliable topic is lost without an error: a reader checks that the
sequence numbers of each service arrive without gaps and that what the credits
say was published does arrive (iceoryx2 skips a publisher it cannot connect to,
for example when the process is out of file descriptors, without telling the
receiver; that is the silent loss this check turns into a
:class:`~hetros.TransportError`).

Resources per endpoint: one iceoryx2 service (2 file descriptors) and one port
(1 for a subscriber, 4 for a publisher, 3 more per connection); per node one
wake channel (5); per process one back channel and one thread.

Every sample starts with a 16-byte header (sequence number, publisher slot,
reserved); the message follows in the codec's format (CDR for messages).
"""


from ._domain import ShmDomain, Unacknowledged, remove_session_segments
from ._endpoints import ShmReader, ShmWriter, has_loan
from ._events import WakeChannel, raise_open_file_limit
from ._iceoryx import iox2, new_node
from ._sample import SESSION_TAG_VARIABLE, check_room, new_session, reserved_bytes
from ._transport import ShmTransport


def cleanup_stale() -> list[str]:
    """Clean up after crashed launches (``_stale.py``): the launcher's part, loaded there only."""
    from ._stale import cleanup_stale as clean

    return clean()


__all__ = [
    "SESSION_TAG_VARIABLE",
    "ShmDomain",
    "ShmReader",
    "ShmTransport",
    "ShmWriter",
    "Unacknowledged",
    "WakeChannel",
    "check_room",
    "cleanup_stale",
    "has_loan",
    "iox2",
    "new_node",
    "new_session",
    "raise_open_file_limit",
    "remove_session_segments",
    "reserved_bytes",
]
