"""The dds transport as the runtime sees it: the plan's edges between hosts of one graph."""

from __future__ import annotations

import threading
import time

from ..._log import get_logger
from .._base import Wake
from .._seam import Endpoint, Transport, TransportContext
from ._domain import HOST_LEASE, DdsDomain
from ._edges import DdsEdgeReader, DdsEdgeWriter, edge_topic

log = get_logger("hetros.graph")


class DdsTransport(Transport):
    """Edges to other hosts: one DDS writer per channel and process (every node of the process
    writes through it), one reader per subscribing endpoint over the publishing hosts' topics."""

    kind = "dds"

    def __init__(self, context: TransportContext) -> None:
        super().__init__(context)
        plan = context.plan
        if plan is None or not plan.local_host:
            raise AssertionError("dds edges come from a plan with hosts")
        self._plan = plan
        self._lock = threading.Lock()
        self._domain: DdsDomain | None = None
        self._writers: dict[str, DdsEdgeWriter] = {}
        self._readers: list[tuple[str, DdsEdgeReader]] = []

    def domain(self) -> DdsDomain:
        with self._lock:
            if self._domain is None:
                hosts = self._plan.hosts
                self._domain = DdsDomain(self._plan.dds_domain, interface=hosts[self._plan.local_host].address,
                                         peers=[h.address for h in hosts.values()], lease=HOST_LEASE,
                                         configured_at=f"hosts.{self._plan.local_host}.address")
            return self._domain

    def open_writer(self, endpoint: Endpoint) -> DdsEdgeWriter:
        writer = self._writers.get(endpoint.name)
        if writer is None:
            writer = DdsEdgeWriter(self.domain(), edge_topic(self._plan.name, self._plan.local_host, endpoint.name),
                                   self.context.codec(endpoint.typename, endpoint.envelope), endpoint.qos)
            with self._lock:
                writer = self._writers.setdefault(endpoint.name, writer)
        return writer

    def open_reader(self, endpoint: Endpoint, wake: Wake) -> DdsEdgeReader:
        other_hosts = sorted({self._plan.host_of(edge.publisher) for edge in endpoint.edges})
        topics = [edge_topic(self._plan.name, host, endpoint.name) for host in other_hosts]
        reader = DdsEdgeReader(self.domain(), topics, self.context.codec(endpoint.typename, endpoint.envelope),
                               endpoint.qos, wake)
        with self._lock:
            self._readers.append((f"{endpoint.name} from {', '.join(other_hosts)}", reader))
        return reader

    def prepare(self, nodes: list[str]) -> None:
        """Writers to other hosts exist before the nodes run, so remote readers match them meanwhile."""
        for edge in self._plan.edges:
            if edge.transport == "dds" and edge.publisher in nodes:
                channel = self._plan.channels[edge.channel]
                self.open_writer(Endpoint(channel.name, edge.publisher, channel.type, channel.qos,
                                          channel.kind != "topic"))

    def wait_matched(self, timeout: float) -> list[str]:
        with self._lock:
            writers = dict(self._writers)
        if not writers:
            return []
        plan = self._plan
        expected = {name: len({e.subscriber for e in plan.edges if e.channel == name and e.transport == "dds"
                               and plan.host_of(e.publisher) == plan.local_host})
                    for name in writers}
        deadline = time.monotonic() + timeout
        while not self.context.stop.is_set():
            short = [n for n, w in writers.items() if w.matched() < expected[n]]
            if not short or time.monotonic() > deadline:
                for name in short:
                    log.warning("%s: %d of %d remote subscribers matched after %g s; publishing anyway",
                                name, writers[name].matched(), expected[name], timeout)
                return short
            time.sleep(0.01)
        return []

    def linger(self) -> list[str]:
        with self._lock:
            writers = dict(self._writers)
        return [f"reliable topic {name}: a subscriber on another host did not acknowledge every message "
                "within publish_timeout; the rest may be lost as this process ends"
                for name, writer in writers.items() if not writer.linger(self.context.stop)]

    def close(self) -> None:
        with self._lock:
            domain, self._domain = self._domain, None
            writers, self._writers = self._writers, {}
            readers, self._readers = self._readers, []
        for name, writer in writers.items():
            log.info("dds: sent %d samples of %s to other hosts", writer.sent, name)
        for what, reader in readers:
            log.info("dds: received %d samples of %s", reader.received, what)
        if domain is not None:
            domain.close()
