"""Malformed input, 10,350 connections of it, against a running hetros ROS 1 node and `hetros master`.

The node runs on a `kind: ros1` target under `hetros launch`: it publishes /chatter and
serves /set_bool. Each hypothesis example opens one connection and sends one bad input:
TCPROS headers (random bytes, bad fields, lengths up to 4 GiB, cut off), service request
frames after a good handshake, XML-RPC bodies to the node's slave API and to the master;
then slowloris-style partial writes held open. After each phase: the node and the master
still run, a good subscriber still receives, a good client still gets answers, threads and
memory are back within bounds. Needs no ROS 1 installation: hetros's own peer is the good client.
"""

from __future__ import annotations

import http.client
import os
import socket
import struct
import subprocess
import sys
import textwrap
import time
import xmlrpc.client
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hetros.interfaces.std_srvs.srv import SetBool
from hetros.msg import registry
from hetros.transport.tcpros import Ros1Peer, Ros1ServiceType, Ros1Type
from hetros.transport.tcpros._header import encode_header
from tests.support.ros1 import free_port

EXAMPLES = 3400  # per fuzzed phase; three of them, then 150 slowloris connections
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
NODES = textwrap.dedent('''
    from hetros.interfaces.std_msgs.msg import String
    from hetros.interfaces.std_srvs.srv import SetBool

    def target(node):
        pub = node.create_publisher(String, "/chatter")
        node.create_service(SetBool, "/set_bool", lambda req: SetBool.Response(success=req.data))
        node.create_timer(0.02, lambda: pub.publish(String(data="still here")))
        node.spin()
''')
STRING_MD5 = "992ce8a1687cec8c8bd883ec73ca41d1"


@dataclass
class Graph:
    master_uri: str
    master_pid: int
    node_pid: int
    slave_uri: str
    tcpros: tuple[str, int]
    rosrpc: tuple[str, int]
    peer: Ros1Peer
    received: list[str]


def _status(pid: int, key: str) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1])
    raise KeyError(key)


def _address(uri: str) -> tuple[str, int]:
    host, _, port = uri.split("://", 1)[1].rstrip("/").rpartition(":")
    return host, int(port)


@pytest.fixture(scope="module")
def graph(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Graph]:
    root = tmp_path_factory.mktemp("fuzz")
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    master = subprocess.Popen([sys.executable, "-m", "hetros", "master", "--port", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    (root / "nodes.py").write_text(NODES)
    (root / "project.yaml").write_text(textwrap.dedent(f"""
        name: fuzzed
        targets: {{ros1: {{kind: ros1}}}}
        nodes:
          target: {{run: nodes:target, target: ros1, publish: {{/chatter: std_msgs/msg/String}},
                   services: {{/set_bool: std_srvs/srv/SetBool}}}}
        external:
          ros1: {{master: '{uri}'}}
    """))
    log = (root / "launch.log").open("w")
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(root / "project.yaml")], cwd=root,
                              stdout=log, stderr=subprocess.STDOUT, text=True)
    api = xmlrpc.client.ServerProxy(uri)
    deadline = time.monotonic() + 30
    while True:
        try:
            code, _, rosrpc = api.lookupService("/fuzz", "/set_bool")
            if code == 1:
                break
        except OSError:
            pass
        assert time.monotonic() < deadline and launch.poll() is None, "the fuzzed graph did not come up"
        time.sleep(0.2)
    slave = api.lookupNode("/fuzz", "/target")[2]
    node_pid = xmlrpc.client.ServerProxy(slave).getPid("/fuzz")[2]
    protocol = xmlrpc.client.ServerProxy(slave).requestTopic("/fuzz", "/chatter", [["TCPROS"]])[2]
    types = registry()
    received: list[str] = []
    peer = Ros1Peer("/fuzz_good_peer", uri)
    peer.subscribe("/chatter", Ros1Type(types, "std_msgs/msg/String"), lambda m: received.append(m.data))
    try:
        yield Graph(uri, master.pid, node_pid, slave, (protocol[1], int(protocol[2])), _address(rosrpc), peer,
                    received)
    finally:
        peer.close()
        launch.terminate()
        launch.wait(30)
        log.close()
        master.terminate()
        master.wait(10)
    output = (root / "launch.log").read_text()
    assert "Traceback" not in output, output[-3000:]
    assert output.count("\n") < 1000, "refused connections flooded the log"


def _still_served(graph: Graph) -> None:
    """The node and the master run, a good subscriber receives, a good client is answered."""
    assert os.path.exists(f"/proc/{graph.node_pid}") and os.path.exists(f"/proc/{graph.master_pid}")
    before = len(graph.received)
    deadline = time.monotonic() + 5
    while len(graph.received) <= before and time.monotonic() < deadline:
        time.sleep(0.02)
    assert len(graph.received) > before, "the good subscriber stopped receiving"
    kind = Ros1ServiceType(registry(), "std_srvs/srv/SetBool")
    assert graph.peer.call_service("/set_bool", kind, SetBool.Request(data=True)).success
    code, _, _ = xmlrpc.client.ServerProxy(graph.master_uri).getSystemState("/fuzz")
    assert code == 1


SENT: list[int] = []


def _exchange(address: tuple[str, int], data: bytes, hang_up: bool) -> bytes:
    """Send ``data``; read what comes back until the server closes, for at most 2 s (a header that
    happens to be good subscribes, and then messages keep coming), or hang up at once."""
    SENT.append(len(data))
    with socket.create_connection(address, timeout=2) as sock:
        try:
            sock.sendall(data)
        except OSError:
            return b""  # the server closed early: what we want
        if hang_up:
            return b""
        try:
            sock.shutdown(socket.SHUT_WR)
        except OSError:
            return b""  # the server refused and reset the connection already
        got = b""
        deadline = time.monotonic() + 2
        try:
            while time.monotonic() < deadline and (chunk := sock.recv(65536)):
                got += chunk
        except OSError:
            pass
        return got


def _frame(body: bytes, length: int | None = None) -> bytes:
    return struct.pack("<I", len(body) if length is None else length) + body


def _field(name: bytes, value: bytes, length: int | None = None) -> bytes:
    raw = name + b"=" + value
    return struct.pack("<I", len(raw) if length is None else length) + raw


_names = st.sampled_from([b"callerid", b"topic", b"md5sum", b"type", b"message_definition", b"tcp_nodelay",
                          b"service", b"persistent", b"probe", b"latching", b"error", b""]) | st.binary(max_size=12)
_values = st.sampled_from([b"/chatter", b"/set_bool", b"/nope", STRING_MD5.encode(), b"*", b"std_msgs/String",
                           b"1", b"\xff\xfe", b"=" * 5]) | st.binary(max_size=40)
_lengths = st.none() | st.sampled_from([0, 1, 3, 2**20 + 1, 2**31, 2**32 - 1]) | st.integers(0, 2**32 - 1)


@st.composite
def tcpros_headers(draw: st.DrawFn) -> tuple[bytes, bool]:
    """A bad connection header: garbage, or fields with wrong names, values, lengths; maybe cut off."""
    if draw(st.booleans()):
        data = draw(st.binary(max_size=200))
    else:
        fields = b"".join(_field(draw(_names), draw(_values), draw(_lengths) if draw(st.integers(0, 5)) == 0 else None)
                          for _ in range(draw(st.integers(0, 6))))
        data = _frame(fields, draw(_lengths) if draw(st.booleans()) else None)
    cut = draw(st.integers(0, len(data)))
    return data[:cut] if draw(st.booleans()) else data, draw(st.booleans())


def test_bad_tcpros_headers_are_refused_and_the_node_goes_on(graph: Graph) -> None:
    @FUZZ
    @given(tcpros_headers())
    def one(case: tuple[bytes, bool]) -> None:
        data, hang_up = case
        _exchange(graph.tcpros, data, hang_up)

    one()
    _still_served(graph)


@st.composite
def service_requests(draw: st.DrawFn) -> tuple[bytes, bool]:
    """A good ROSRPC handshake, then request frames with garbage bodies and wrong lengths."""
    kind = Ros1ServiceType(registry(), "std_srvs/srv/SetBool")
    header = encode_header({"callerid": "/fuzz", "service": "/set_bool", "md5sum": kind.md5,
                            "persistent": draw(st.sampled_from(["0", "1"]))})
    frames = b"".join(_frame(draw(st.binary(max_size=64)), draw(_lengths) if draw(st.booleans()) else None)
                      for _ in range(draw(st.integers(1, 3))))
    return header + frames, draw(st.booleans())


def test_bad_service_requests_are_refused_and_the_node_goes_on(graph: Graph) -> None:
    @FUZZ
    @given(service_requests())
    def one(case: tuple[bytes, bool]) -> None:
        data, hang_up = case
        _exchange(graph.rosrpc, data, hang_up)

    one()
    _still_served(graph)


_methods = st.sampled_from(["getPid", "getBusInfo", "getBusStats", "getSubscriptions", "publisherUpdate",
                            "requestTopic", "paramUpdate", "getMasterUri", "registerPublisher", "lookupNode",
                            "getParam", "setParam", "searchParam", "getSystemState", "no_such_method",
                            "__init__", "_peer", "system.listMethods"]) | st.text(max_size=20)
_params = st.recursive(st.none() | st.booleans() | st.integers(-(2**31), 2**31 - 1) | st.text(max_size=20)
                       | st.binary(max_size=20), lambda inner: st.lists(inner, max_size=4), max_leaves=8)


@st.composite
def xmlrpc_bodies(draw: st.DrawFn) -> tuple[bytes, str, bool]:
    """An HTTP POST to an XML-RPC server: garbage, broken XML, or calls with wrong arguments."""
    choice = draw(st.integers(0, 2))
    if choice == 0:
        body = draw(st.binary(max_size=300))
    elif choice == 1:
        body = draw(st.sampled_from([b"<?xml version='1.0'?><methodCall>", b"<methodCall><methodName>",
                                     b"<!DOCTYPE x [<!ENTITY a 'aaaa'>]><methodCall/>", b"<a>" * 50]))
        body += draw(st.binary(max_size=50))
    else:
        params = tuple(draw(st.lists(_params, max_size=4)))
        try:
            body = xmlrpc.client.dumps(params, draw(_methods), allow_none=True).encode()
        except (TypeError, ValueError, OverflowError):
            body = b"<methodCall/>"
    length = str(len(body)) if draw(st.integers(0, 3)) else draw(st.sampled_from(["-1", "x", "4294967296",
                                                                                   "99999999999", ""]))
    target = draw(st.sampled_from(["master", "node"]))
    return f"POST /RPC2 HTTP/1.0\r\nContent-Type: text/xml\r\nContent-Length: {length}\r\n\r\n".encode() + body, \
        target, draw(st.booleans())


def test_bad_xmlrpc_is_refused_by_the_master_and_the_node(graph: Graph) -> None:
    servers = {"master": _address(graph.master_uri), "node": _address(graph.slave_uri)}

    @FUZZ
    @given(xmlrpc_bodies())
    def one(case: tuple[bytes, str, bool]) -> None:
        data, target, hang_up = case
        _exchange(servers[target], data, hang_up)

    one()
    _still_served(graph)


def test_slowloris_and_huge_lengths_tie_up_nothing_for_long(graph: Graph) -> None:
    """Partial writes held open, and lengths promising 4 GiB: served alongside, then dropped."""
    threads = {pid: _status(pid, "Threads") for pid in (graph.node_pid, graph.master_pid)}
    memory = {pid: _status(pid, "VmRSS") for pid in (graph.node_pid, graph.master_pid)}
    openers = [
        (graph.tcpros, b"\x40\x00\x00\x00\x10\x00\x00\x00callerid=/slo"),
        (graph.tcpros, struct.pack("<I", 2**32 - 1)),
        (graph.rosrpc, encode_header({"callerid": "/slo", "service": "/set_bool", "md5sum": "*",
                                      "persistent": "1"}) + struct.pack("<I", 2**30) + b"\x01"),
        (_address(graph.master_uri), b"POST /RPC2 HTTP/1.0\r\nContent-Length: 4294967296\r\n\r\n<?xml"),
        (_address(graph.slave_uri), b"POST /RPC2 HTTP/1.0\r\nContent-Len"),
    ]
    held = []
    for address, data in openers * 30:
        sock = socket.create_connection(address, timeout=30)
        sock.sendall(data)
        held.append(sock)
    _still_served(graph)  # the good peers are served while 150 connections dawdle
    closed = [False] * len(held)
    deadline = time.monotonic() + 25
    while not all(closed) and time.monotonic() < deadline:
        for index, sock in enumerate(held):
            if not closed[index]:
                sock.settimeout(0.01)
                try:
                    closed[index] = sock.recv(1024) == b"" or closed[index]
                except TimeoutError:
                    pass
                except OSError:
                    closed[index] = True
        time.sleep(0.2)
    for sock in held:
        sock.close()
    assert all(closed), f"{closed.count(False)} of {len(held)} dawdling connections were never closed"
    time.sleep(0.5)
    for pid, count in threads.items():
        assert _status(pid, "Threads") <= count + 4, f"pid {pid} kept threads of dropped connections"
        assert _status(pid, "VmRSS") < memory[pid] + 64 * 1024, f"pid {pid} grew by more than 64 MiB"
    _still_served(graph)


def test_a_good_xmlrpc_call_still_works_after_over_10000_bad_inputs(graph: Graph) -> None:
    assert len(SENT) >= 10_000, f"only {len(SENT)} malformed inputs were sent"
    conn = http.client.HTTPConnection(*_address(graph.master_uri), timeout=5)
    body = xmlrpc.client.dumps(("/fuzz",), "getSystemState").encode()
    conn.request("POST", "/RPC2", body, {"Content-Type": "text/xml"})
    assert conn.getresponse().status == 200
