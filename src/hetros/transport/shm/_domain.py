"""One process' view of the shared-memory fabric of a launch, and the clean-up after it."""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..._errors import Error, TransportError
from ..._qos import QoS
from .._base import Codec, Wake
from ._endpoints import ShmReader, ShmWriter
from ._events import (
    BackChannel,
    WakeChannel,
    back_channel_name,
    event_service,
    fd_hint,
    raise_open_file_limit,
    wake_channel_name,
)
from ._iceoryx import file_prefix, iox2, new_node
from ._sample import (
    MAX_SUBSCRIBER_SLOTS,
    SHM_DIR,
    segment_prefix,
)
from ._service import Service

# how often a lingering process rereads its subscribers' progress (a shutdown path, not a hot one)
LINGER_POLL = 0.005


@dataclass(frozen=True)
class Unacknowledged:
    """Messages a reliable publisher sent that subscriber ``slot`` (in process ``pid``) never took."""

    topic: str
    slot: int
    pid: int
    count: int


class ShmDomain:
    """This process' view of the shared-memory fabric of one launch ("session")."""

    def __init__(self, session: str, process_name: str) -> None:
        raise_open_file_limit()
        self.session = session
        self.process_name = process_name
        self._lock = threading.Lock()
        try:
            self._node = new_node(f"hetros-{session}-{process_name}")
        except Error:
            raise
        except Exception as exc:  # iceoryx2 raises its own exception classes
            raise TransportError(node_failure(exc)) from exc
        self._services: dict[str, Service] = {}
        self._readers: list[ShmReader] = []
        self._channels: dict[str, WakeChannel] = {}
        self._notifiers: dict[int, Any] = {}
        self._back_notifiers: dict[str, Any] = {}
        self._back: BackChannel | None = None
        self._closed = False

    def _service(self, topic: str, publisher_target: str, qos: QoS) -> Service:
        key = f"{topic}@{publisher_target}"
        with self._lock:
            service = self._services.get(key)
            if service is None:
                service = Service(self, self._node, topic, publisher_target, qos)
                self._services[key] = service
            return service

    def wake_channel(self, owner: str) -> WakeChannel:
        """The wake channel of node ``owner`` in this process (created on first use)."""
        with self._lock:
            channel = self._channels.get(owner)
            if channel is None:
                channel = WakeChannel(self._node, self.session, owner)
                self._channels[owner] = channel
            return channel

    def notifier(self, key: int, event: int) -> tuple[Any, Any]:
        """How to wake reader ``event`` of the node whose wake channel is ``key``: call ``f(arg)``."""
        notifier = self._notifiers.get(key)
        if notifier is None:
            service = event_service(self._node, wake_channel_name(self.session, key), "wake channel of a subscriber")
            notifier = service.notifier_builder().create()
            self._notifiers[key] = notifier
        return notifier.notify_with_custom_event_id, iox2.EventId.new(event)

    def notify_back(self, publisher_target: str, event: int) -> None:
        """Tell the publishing process of a service that one of its subscribers took or joined
        (``event`` 0: the publisher has no back channel event yet, or its word was damaged)."""
        if not event:
            return
        notifier = self._back_notifiers.get(publisher_target)
        if notifier is None:
            service = event_service(self._node, back_channel_name(self.session, publisher_target),
                                     f"back channel of target {publisher_target!r}")
            notifier = service.notifier_builder().create()
            self._back_notifiers[publisher_target] = notifier
        notifier.notify_with_custom_event_id(iox2.EventId.new(event))

    def back_channel(self) -> BackChannel:
        with self._lock:
            if self._back is None:
                self._back = BackChannel(self._node, self.session, self.process_name)
            return self._back

    def open_writer(self, topic: str, target: str, qos: QoS, codec: Codec, slot: int = 0) -> ShmWriter:
        return ShmWriter(self._service(topic, target, qos), codec, slot)

    def open_reader(
        self,
        topic: str,
        publisher_targets: Sequence[str],
        qos: QoS,
        codec: Codec,
        slot: int,
        wake: Wake,
        owner: str,
    ) -> ShmReader:
        """A reader in subscriber ``slot`` of the topic; ``wake`` runs when ``owner``'s wake channel fires."""
        if not 0 <= slot < MAX_SUBSCRIBER_SLOTS:
            raise TransportError(
                f"subscriber slot of {topic} must be in 0..{MAX_SUBSCRIBER_SLOTS - 1}, not {slot!r}: "
                f"a topic carries at most {MAX_SUBSCRIBER_SLOTS} cross-process subscribers"
            )
        services = [self._service(topic, target, qos) for target in publisher_targets]
        reader = ShmReader(self, services, codec, slot, wake, self.wake_channel(owner))
        self._readers.append(reader)
        return reader

    def linger(self, stop: threading.Event) -> list[Unacknowledged]:
        """Wait until every subscriber has taken what this process published on reliable topics.

        iceoryx2 frees a publisher's samples with its process, so a process whose nodes have
        all returned must not end before its subscribers took what it sent, as a DDS reliable
        writer lingers until acknowledged. It waits while subscribers take from any of its
        topics (one working through a thousand topics reaches the last one late); a topic is
        given up once nothing of this process was taken for that topic's ``publish_timeout``,
        and what is left is returned. ``stop`` (the graph shutting down) ends the wait at once.
        """
        with self._lock:
            waiting = {service: service.behind() for service in self._services.values()}
        waiting = {service: behind for service, behind in waiting.items() if behind}
        progress = time.monotonic()
        left: list[Unacknowledged] = []
        while waiting and not stop.wait(LINGER_POLL):
            now = time.monotonic()
            for service, before in list(waiting.items()):
                behind = service.behind()
                if not behind:
                    del waiting[service]
                    progress = now
                elif behind != before:
                    waiting[service], progress = behind, now
            for service, behind in list(waiting.items()):
                if now - progress > service.qos.publish_timeout:
                    del waiting[service]
                    left += [Unacknowledged(service.topic, slot, pid, count) for slot, pid, count in behind]
        return left

    def close(self) -> None:
        with self._lock:
            if self._closed:
                return
            self._closed = True
            services = list(self._services.values())
            self._services.clear()
            back, self._back = self._back, None
        for reader in list(self._readers):
            reader.close()
        self._readers.clear()
        if back is not None:
            back.close()
        for service in services:
            service.close()
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()
        self._notifiers.clear()
        self._back_notifiers.clear()
        # iceoryx2 removes a node's shared memory when its last handle is dropped
        self._node = None


def node_failure(exc: Exception) -> str:
    """What to do when this process cannot join iceoryx2 (its node)."""
    text = f"{type(exc).__name__}: {exc}"
    if "UniqueNodeId" in text:
        counters = (", ".join(str(p) for p in SHM_DIR.glob(f"{file_prefix()}*global_mgmt"))
                    or f"/dev/shm/{file_prefix()}*global_mgmt")
        return (f"iceoryx2 could not give this process a node id ({text}): its machine-wide node counter "
                f"({counters}) is damaged, most likely written by another process; stop every hetros and "
                "iceoryx2 process, then remove that file (its owner or root can); the next launch makes a new one")
    return f"this process could not join iceoryx2's shared memory ({text}); {fd_hint()}"


def remove_session_segments(session: str) -> list[str]:
    """Unlink every credits file of a session (the launcher calls it on the way out)."""
    removed: list[str] = []
    for path in SHM_DIR.glob(f"{segment_prefix(session)}*"):
        _unlink(path, removed)
    return removed


def _unlink(path: Path, removed: list[str]) -> None:
    try:
        path.unlink()
        removed.append(path.name)
    except FileNotFoundError:
        pass
