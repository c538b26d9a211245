"""One DDS participant per process, configured from the project file, and its QoS.

Discovery is static and loopback by default: multicast off, the peers the project
file names (``127.0.0.1`` unless it says otherwise), one interface. A user who
already runs ROS 2 with their own Cyclone configuration sets ``CYCLONEDDS_URI``
as for any ROS 2 node, and hetros then takes that file instead.
"""

from __future__ import annotations

import fcntl
import os
import socket
import stat
import struct
import threading
from collections.abc import Callable, Sequence
from typing import Any
from xml.sax.saxutils import quoteattr

from cyclonedds.core import DDSException, Policy, Qos
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from ..._errors import TransportError
from ..._log import get_logger
from ..._qos import QoS
from ._waiter import Waiter

# ROS 2's domains are 0..232 (ports are computed from them)
MAX_DOMAIN_ID = 232
# stock ROS 2 peers only accept XCDR1: a writer offering XCDR2 is discovered and never matched
_XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)

log = get_logger("hetros.dds")

_domains_lock = threading.Lock()
_domains: dict[int, Domain] = {}


def default_domain_id() -> int:
    """``ROS_DOMAIN_ID`` as ROS 2 reads it, else 0."""
    text = os.environ.get("ROS_DOMAIN_ID", "").strip()
    if not text:
        return 0
    if not text.isdigit() or int(text) > MAX_DOMAIN_ID:
        raise TransportError(f"ROS_DOMAIN_ID must be a number from 0 to {MAX_DOMAIN_ID}, not {text!r}")
    return int(text)


def config_xml(interface: str, peers: Sequence[str], multicast: bool, lease: float | None = None) -> str:
    """The Cyclone configuration of a hetros participant; ``lease`` (seconds) is how soon peers
    give up on it when it vanishes (Cyclone's default is 10 s)."""
    peer_lines = "".join(f"<Peer address={quoteattr(peer)}/>" for peer in peers)
    # a short lease needs announcements more often than it (Cyclone's default interval is 30 s)
    lease_line = (f"<LeaseDuration>{lease:g}s</LeaseDuration><SPDPInterval>{lease / 4:g}s</SPDPInterval>"
                  if lease else "")
    return (
        "<CycloneDDS><Domain Id=\"any\"><General>"
        f"<Interfaces><NetworkInterface address={quoteattr(interface)}/></Interfaces>"
        f"<AllowMulticast>{'true' if multicast else 'false'}</AllowMulticast>"
        "</General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
        "<MaxAutoParticipantIndex>100</MaxAutoParticipantIndex>"
        f"<Peers>{peer_lines}</Peers>{lease_line}</Discovery>"
        # multi-MB samples arrive as many fragments: a small socket buffer loses them
        "<Internal><SocketReceiveBufferSize min=\"default\" max=\"4MiB\"/></Internal>"
        + _tracing()
        + "</Domain></CycloneDDS>"
    )


def _tracing() -> str:
    """``HETROS_DDS_TRACE=<file>``: Cyclone's discovery trace (per process: ``<file>.<pid>``), for
    finding out why peers do not see each other."""
    path = os.environ.get("HETROS_DDS_TRACE", "")
    if not path:
        return ""
    return (f"<Tracing><Verbosity>fine</Verbosity><OutputFile>{quoteattr(f'{path}.{os.getpid()}')[1:-1]}"
            "</OutputFile></Tracing>")


def dds_qos(qos: QoS, user_data: bytes = b"") -> Qos:
    """A hetros QoS as DDS policies, one to one; except that a reliable writer never blocks inside
    DDS (the binding would hold the GIL): ``publish_timeout`` is waited out by ``write_sample``."""
    policies: list[Any] = [
        Policy.Reliability.Reliable(max_blocking_time=0)
        if qos.reliability == "reliable" else Policy.Reliability.BestEffort,
        Policy.History.KeepAll if qos.history == "keep_all" else Policy.History.KeepLast(qos.depth),
        Policy.Durability.TransientLocal if qos.durability == "transient_local" else Policy.Durability.Volatile,
        _XCDR1,
    ]
    if qos.deadline is not None:
        policies.append(Policy.Deadline(duration(seconds=qos.deadline)))
    if qos.lifespan is not None:
        policies.append(Policy.Lifespan(duration(seconds=qos.lifespan)))
    if qos.liveliness != "automatic" or qos.lease_duration is not None:
        lease = duration(seconds=qos.lease_duration) if qos.lease_duration is not None else duration(infinite=True)
        policies.append(Policy.Liveliness.ManualByTopic(lease) if qos.liveliness == "manual_by_topic"
                        else Policy.Liveliness.Automatic(lease))
    if user_data:
        policies.append(Policy.Userdata(data=user_data))
    return Qos(*policies)


# how soon the hosts of one graph notice that one of them vanished (seconds; Cyclone's default is 10)
HOST_LEASE = 1.0

# ROS 2's default service QoS (rmw_qos_profile_services_default)
SERVICE_QOS = QoS(reliability="reliable", history="keep_last", depth=10, durability="volatile")


def _make_domain(domain_id: int, config: str) -> Domain:
    try:
        return Domain(domain_id, config)
    except DDSException as exc:
        if exc.code != DDSException.DDS_RETCODE_PRECONDITION_NOT_MET:
            raise
        # Cyclone refuses a second Domain object for a domain that already exists in the process
        raise TransportError(
            f"DDS domain {domain_id} already exists in this process with a configuration hetros did not "
            "make (some other code created a DomainParticipant on it first), so hetros cannot apply its own "
            "interface and peers; create hetros's nodes before that code does, or set CYCLONEDDS_URI so both "
            "use one configuration") from exc


class DdsDomain:
    """A participant on one DDS domain and the topics created on it (shared by name)."""

    def __init__(self, domain_id: int | None = None, *, interface: str = "127.0.0.1",
                 peers: Sequence[str] = ("127.0.0.1",), multicast: bool = False, lease: float | None = None,
                 configured_at: str = "external.ros2.interface") -> None:
        self.domain_id = default_domain_id() if domain_id is None else domain_id
        if not 0 <= self.domain_id <= MAX_DOMAIN_ID:
            raise TransportError(f"a ROS 2 domain id must be 0 to {MAX_DOMAIN_ID}, not {self.domain_id!r}")
        self.configured_by = os.environ.get("CYCLONEDDS_URI", "") or "hetros (static peers " + ", ".join(peers) + ")"
        try:
            if not os.environ.get("CYCLONEDDS_URI"):
                with _domains_lock:
                    if self.domain_id not in _domains:
                        _domains[self.domain_id] = _make_domain(self.domain_id,
                                                                config_xml(interface, peers, multicast, lease))
            # rmw_cyclonedds announces the security enclave in the participant's USER_DATA
            self.participant = DomainParticipant(self.domain_id, qos=Qos(Policy.Userdata(data=b"enclave=/;")))
            if not os.environ.get("CYCLONEDDS_URI"):
                pin_receive_sockets(interface, self.domain_id)
        except DDSException as exc:
            raise TransportError(f"cannot join DDS domain {self.domain_id} on {interface}: {exc}; {interface} must be "
                                 f"an address of this machine: check {configured_at} in the project file (or "
                                 "CYCLONEDDS_URI)") from exc
        self._topics: dict[str, Topic[Any]] = {}
        self._lock = threading.Lock()
        # the instance handles of this participant's topic writers
        self.local_writers: set[int] = set()
        self._waiter: Waiter | None = None

    def watch(self, reader: Any, handler: Callable[[], None], unread_only: bool = False) -> None:
        """Run ``handler`` (on this participant's waiting thread) whenever ``reader`` has data
        (``unread_only``: samples not read yet; see ``Waiter.watch``)."""
        with self._lock:
            if self._waiter is None:
                self._waiter = Waiter(self.participant, str(self.domain_id))
            waiter = self._waiter
        waiter.watch(reader, handler, unread_only)

    def topic(self, name: str, data_type: Any) -> Topic[Any]:
        with self._lock:
            topic = self._topics.get(name)
            if topic is None:
                topic = self._topics[name] = Topic(self.participant, name, data_type, qos=Qos(_XCDR1))
            elif topic.data_type is not data_type:
                raise TransportError(f"DDS topic {name} already carries {topic.data_type.__idl_typename__}, "
                                     f"not {data_type.__idl_typename__}")
            return topic

    @property
    def gid(self) -> bytes:
        return participant_gid(self.participant)

    def close(self) -> None:
        """Deletes the participant and with it every reader and writer it made (Cyclone waits for
        listeners that are running), so nothing of it outlives the bridge."""
        with self._lock:
            waiter, self._waiter = self._waiter, None
        if waiter is not None:
            waiter.close()
        participant, self.participant = self.participant, None  # type: ignore[assignment]
        if participant is not None:
            self._topics.clear()
            delete_entity(participant)


def _device_of(address: str) -> str:
    """The network device that owns ``address`` (``lo`` for 127.0.0.1)."""
    packed = socket.inet_aton(socket.gethostbyname(address))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        for _index, name in socket.if_nameindex():
            try:
                request = struct.pack("256s", name.encode()[:15])
                answer = fcntl.ioctl(probe.fileno(), _SIOCGIFADDR, request)
            except OSError:
                continue  # a device without an IPv4 address
            if answer[20:24] == packed:
                return name
    raise TransportError(f"no network device of this machine has the address {address}; name one it has "
                         "(interface: under external: ros2:, or the host's address under hosts:)")


_SIOCGIFADDR = 0x8915
_warned_unpinned = False


def pin_receive_sockets(interface: str, domain_id: int) -> list[int]:
    """Make Cyclone's receive sockets take packets only from ``interface``'s device.

    Cyclone binds its receive sockets to the wildcard address whatever the configuration
    says (it sends only from the chosen interface, but would accept packets from any), so
    that a participant meant for loopback would listen on every network. hetros pins those
    sockets (the domain's ports, bound to 0.0.0.0, in this process) to the interface's device
    with SO_BINDTODEVICE; returns the ports pinned. Where the kernel refuses (it may want
    CAP_NET_RAW), it says so once: firewall the domain's ports there.
    """
    global _warned_unpinned
    device = _device_of(interface)
    first, last = 7400 + 250 * domain_id, 7400 + 250 * domain_id + 249
    pinned = []
    for entry in os.listdir("/proc/self/fd"):
        try:
            if not stat.S_ISSOCK(os.fstat(int(entry)).st_mode):
                continue
            sock = socket.socket(fileno=os.dup(int(entry)))  # a duplicate: closing it leaves Cyclone's
        except OSError:
            continue
        try:
            if sock.family != socket.AF_INET or sock.type != socket.SOCK_DGRAM:
                continue
            host, port = sock.getsockname()
            if host != "0.0.0.0" or not first <= port <= last:
                continue
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_BINDTODEVICE, device.encode())
            pinned.append(port)
        except PermissionError:
            if not _warned_unpinned:
                _warned_unpinned = True
                log.warning("DDS: Cyclone listens on every interface (UDP ports %d-%d) and this process may not "
                            "restrict it to %s (SO_BINDTODEVICE needs CAP_NET_RAW here); firewall those ports",
                            first, last, device)
            return pinned
        finally:
            sock.close()
    return pinned


def delete_entity(entity: Any) -> None:
    """Delete a DDS entity (and what it owns) now, not when the binding's object is collected."""
    if entity._ref in entity._entities:
        del entity._entities[entity._ref]
        entity._delete(entity._ref)


def participant_gid(entity: Any) -> bytes:
    """The 16 bytes of an entity's DDS GUID: what ROS 2 calls its gid."""
    return bytes(entity.guid.bytes)
