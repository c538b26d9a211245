"""The shm transport as the runtime sees it: the plan's same-host edges on this process' domain."""

from __future__ import annotations

import threading

from .._base import Wake
from .._seam import Endpoint, Transport, TransportContext
from ._domain import ShmDomain
from ._endpoints import ShmReader, ShmWriter
from ._events import WakeChannel


class ShmTransport(Transport):
    """Edges between processes of one host: iceoryx2 services, one per (topic, publishing process)."""

    kind = "shm"

    def __init__(self, context: TransportContext) -> None:
        super().__init__(context)
        self._lock = threading.Lock()
        self._domain: ShmDomain | None = None

    def domain(self) -> ShmDomain:
        with self._lock:
            if self._domain is None:
                self._domain = ShmDomain(self.context.session, self.context.process)
            return self._domain

    def open_writer(self, endpoint: Endpoint) -> ShmWriter:
        return self.domain().open_writer(endpoint.name, self.context.process, endpoint.qos,
                                         self.context.codec(endpoint.typename, endpoint.envelope))

    def open_reader(self, endpoint: Endpoint, wake: Wake) -> ShmReader:
        plan = self.context.plan
        assert plan is not None, "shm edges come from a plan"
        publishers = sorted({plan.process_of(edge.publisher) for edge in endpoint.edges})
        slot = plan.channels[endpoint.name].subscribers.index(endpoint.node)
        return self.domain().open_reader(endpoint.name, publishers, endpoint.qos,
                                         self.context.codec(endpoint.typename, endpoint.envelope),
                                         slot, wake, endpoint.node)

    def wait_source(self, node: str) -> WakeChannel | None:
        plan = self.context.plan
        if plan is None or not any(e.transport == "shm" and e.subscriber == node for e in plan.edges):
            return None
        return self.domain().wake_channel(node)

    def linger(self) -> list[str]:
        with self._lock:
            domain = self._domain
        if domain is None:
            return []
        plan = self.context.plan
        lost = []
        for miss in domain.linger(self.context.stop):
            channel = plan.channels.get(miss.topic) if plan is not None else None
            subscriber = (channel.subscribers[miss.slot] if channel is not None
                          and miss.slot < len(channel.subscribers) else f"slot {miss.slot}")
            lost.append(
                f"reliable topic {miss.topic}: subscriber {subscriber!r} (pid {miss.pid}) took nothing "
                f"for publish_timeout and has {miss.count} message(s) of this process left to take; "
                "they are lost as this process ends (make the subscriber take them, or raise "
                f"topics.{miss.topic}.publish_timeout)")
        return lost

    def close(self) -> None:
        with self._lock:
            domain, self._domain = self._domain, None
        if domain is not None:
            domain.close()
