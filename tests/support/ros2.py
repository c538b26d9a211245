"""An independent ROS 2 peer for the interop tests, written directly on the cyclonedds binding.

It shares nothing with hetros's DDS transport: its own Cyclone configuration, its own IDL
classes spelled by hand with ROS 2's type names, the binding's own serializer, and for
services rmw_cyclonedds's request header as explicit fields. What it sees is what a stock
ROS 2 node would see; raw samples are available to assert the bytes themselves.
"""

# no `from __future__ import annotations`: the binding reads the IDL classes' annotations as types
import random
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from cyclonedds._clayer import ddspy_take
from cyclonedds.core import DDSException, InstanceState, Policy, Qos, SampleState, ViewState
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl import types as t
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

_CONFIG = ("<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
           "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
           "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>100</MaxAutoParticipantIndex>"
           "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
           "<Internal><SocketReceiveBufferSize min=\"default\" max=\"4MiB\"/></Internal></Domain></CycloneDDS>")


@dataclass
class String(IdlStruct, typename="std_msgs::msg::dds_::String_"):
    data: str


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32
    nanosec: t.uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Header
    height: t.uint32
    width: t.uint32
    encoding: str
    is_bigendian: t.uint8
    step: t.uint32
    data: t.sequence[t.uint8]


@dataclass
class Log(IdlStruct, typename="rcl_interfaces::msg::dds_::Log_"):
    stamp: Time
    level: t.uint8
    name: str
    msg: str
    file: str
    function: str
    line: t.uint32


@dataclass
class AddTwoIntsRequest(IdlStruct, typename="example_interfaces::srv::dds_::AddTwoInts_Request_"):
    client_guid: t.uint64
    sequence_number: t.int64
    a: t.int64
    b: t.int64


@dataclass
class AddTwoIntsResponse(IdlStruct, typename="example_interfaces::srv::dds_::AddTwoInts_Response_"):
    client_guid: t.uint64
    sequence_number: t.int64
    sum: t.int64


_unused_domains = random.sample(range(2, 102), 100)


def free_domain() -> int:
    """A domain of its own for one test, never handed out twice in one process: a domain that a
    test's peer made in this process cannot be made again with hetros's configuration. Not above
    101: Cyclone's ports are 7400 + 250 × domain, and from domain 102 they fall among the ephemeral
    ports the kernel hands to anyone."""
    if not _unused_domains:
        raise AssertionError("the tests asked for more than 100 DDS domains in one process")
    return _unused_domains.pop()


class Peer:
    """One participant on ``domain``, as a ROS 2 node on loopback would have."""

    _domains: ClassVar[dict[int, Domain]] = {}

    def __init__(self, domain: int) -> None:
        if domain not in Peer._domains:
            try:
                Peer._domains[domain] = Domain(domain, _CONFIG)
            except DDSException:
                pass  # hetros made this domain in this process already (unit tests): loopback as well
        self.participant = DomainParticipant(domain)
        self.qos = Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=5)),
                       Policy.History.KeepAll, Policy.DataRepresentation(use_cdrv0_representation=True))

    def writer(self, name: str, kind: type[Any]) -> DataWriter:
        return DataWriter(self.participant, Topic(self.participant, name, kind, qos=self.qos), qos=self.qos)

    def reader(self, name: str, kind: type[Any], qos: Qos | None = None) -> DataReader:
        return DataReader(self.participant, Topic(self.participant, name, kind, qos=self.qos), qos=qos or self.qos)

    def topic(self, name: str, kind: type[Any]) -> Topic:
        return Topic(self.participant, name, kind, qos=self.qos)


def raw_samples(reader: DataReader) -> list[bytes]:
    """The serialized samples as they arrived (encapsulation included)."""
    taken = ddspy_take(reader._ref, SampleState.Any | ViewState.Any | InstanceState.Any, 1000)
    return [data for data, info in taken if info.valid_data]


def wait_for(condition: Callable[[], Any], timeout: float, what: str) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.02)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")


@dataclass
class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):
    data: t.array[t.uint8, 16]


@dataclass
class NodeEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):
    node_namespace: t.bounded_str[256]
    node_name: t.bounded_str[256]
    reader_gid_seq: t.sequence[Gid]
    writer_gid_seq: t.sequence[Gid]


@dataclass
class ParticipantEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):
    gid: Gid
    node_entities_info_seq: t.sequence[NodeEntitiesInfo]


def latched_qos() -> Qos:
    return Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=5)), Policy.History.KeepLast(1),
               Policy.Durability.TransientLocal, Policy.DataRepresentation(use_cdrv0_representation=True))


def write_project(folder: Path, nodes: str, project: str) -> Path:
    """``nodes.py`` and ``project.yaml`` (dedented) in ``folder``; the project file's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "nodes.py").write_text(nodes)
    (folder / "project.yaml").write_text(textwrap.dedent(project))
    return folder / "project.yaml"


@contextmanager
def launched(project: Path, env: dict[str, str] | None = None, duration: float = 40) -> Iterator[subprocess.Popen[str]]:
    """`hetros launch project` for the length of a test, stopped as Ctrl-C would."""
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project), "--duration", f"{duration:g}"],
                              cwd=project.parent, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True)
    try:
        yield launch
    finally:
        launch.terminate()
        try:
            launch.wait(timeout=15)
        except subprocess.TimeoutExpired:
            launch.kill()
            launch.wait()
