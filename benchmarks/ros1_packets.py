"""Packets of one hetros <-> rospy session over loopback, by phase, as the hardware-TCPROS paper counted them.

    sudo .venv/bin/python benchmarks/ros1_packets.py [--messages 10]

Runs `hetros master`, a hetros talker on a `kind: ros1` target and a stock rospy listener
that takes ``--messages`` messages, while tcpdump records loopback. Every TCP segment
(handshake, data, ACK, FIN) is put in one phase by its ports: registration (anything to or
from the master), requestTopic (the listener calling the talker's slave API), the TCPROS
header exchange (the talker's data connection up to and including the talker's header),
and the data phase (the rest of that connection, reported per message). Needs root (tcpdump)
and Debian's rospy.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import socket
import struct
import subprocess
import sys
import tempfile
import textwrap
import time
import xmlrpc.client
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

NODES = textwrap.dedent('''
    from hetros.interfaces.std_msgs.msg import String

    def talker(node):
        pub = node.create_publisher(String, "/chatter")
        for i in node.rate(20):
            pub.publish(String(data=f"hello {i}"))
''')
LISTENER = textwrap.dedent('''
    import sys, time, rospy
    from std_msgs.msg import String
    got = []
    rospy.init_node("listener")
    rospy.Subscriber("/chatter", String, lambda m: got.append(m.data), tcp_nodelay=True)
    while len(got) < int(sys.argv[1]) and not rospy.is_shutdown():
        time.sleep(0.001)
    rospy.signal_shutdown("done")
    print(len(got))
''')


@contextlib.contextmanager
def _capture(pcap: Path) -> Iterator[None]:
    """tcpdump on loopback around the block."""
    dump = subprocess.Popen(["tcpdump", "-i", "lo", "-w", str(pcap), "-U", "tcp"], stderr=subprocess.DEVNULL)
    time.sleep(1.0)
    try:
        yield
    finally:
        time.sleep(0.5)
        dump.terminate()
        dump.wait(10)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def segments(pcap: Path) -> list[tuple[int, int, int, int]]:
    """(source port, destination port, TCP flags, payload bytes) of every IPv4/TCP packet in a loopback pcap."""
    data = pcap.read_bytes()
    magic = struct.unpack_from("<I", data)[0]
    endian = "<" if magic in (0xA1B2C3D4, 0xA1B23C4D) else ">"
    linktype = struct.unpack_from(endian + "I", data, 20)[0]
    link = {1: 14, 113: 16, 276: 20}.get(linktype)
    if link is None:
        raise SystemExit(f"unexpected pcap link type {linktype}")
    out = []
    pos = 24
    while pos + 16 <= len(data):
        _sec, _usec, captured, _length = struct.unpack_from(endian + "IIII", data, pos)
        packet = data[pos + 16:pos + 16 + captured]
        pos += 16 + captured
        ip = packet[link:]
        if len(ip) < 20 or ip[0] >> 4 != 4 or ip[9] != 6:
            continue
        ihl = (ip[0] & 15) * 4
        total = struct.unpack_from(">H", ip, 2)[0]
        tcp = ip[ihl:]
        source, destination = struct.unpack_from(">HH", tcp)
        offset = (tcp[12] >> 4) * 4
        out.append((source, destination, tcp[13], total - ihl - offset))
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--messages", type=int, default=10)
    args = parser.parse_args(argv)
    if os.geteuid() != 0:
        raise SystemExit("tcpdump needs root")
    tmp = Path(tempfile.mkdtemp(prefix="hetros-packets-"))
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    env = dict(os.environ, ROS_MASTER_URI=uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME=str(tmp))
    ros_env = {k: v for k, v in env.items() if k != "PYTHONPATH"}
    (tmp / "nodes.py").write_text(NODES)
    (tmp / "listener.py").write_text(LISTENER)
    (tmp / "project.yaml").write_text(textwrap.dedent(f"""
        name: packets
        targets: {{ros1: {{kind: ros1}}}}
        nodes:
          talker: {{run: nodes:talker, target: ros1, publish: {{/chatter: std_msgs/msg/String}}}}
        external:
          ros1: {{master: '{uri}'}}
    """))
    master = subprocess.Popen([sys.executable, "-m", "hetros", "master", "--port", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    launch = None
    try:
        deadline = time.monotonic() + 20
        while True:
            try:
                xmlrpc.client.ServerProxy(uri).getPid("/packets")
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise SystemExit("hetros master did not come up") from None
                time.sleep(0.1)
        # capture 1: the talker starts and registers (nobody else talks meanwhile)
        with _capture(tmp / "talker.pcap"):
            launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp / "project.yaml")],
                                      cwd=tmp, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            time.sleep(5.0)
        talker_api = xmlrpc.client.ServerProxy(uri).lookupNode("/packets", "/talker")[2]
        talker_slave = int(talker_api.rstrip("/").rsplit(":", 1)[1])
        talker_tcpros = int(xmlrpc.client.ServerProxy(talker_api).requestTopic(
            "/packets", "/chatter", [["TCPROS"]])[2][2])
        # capture 2: a stock rospy listener joins, takes the messages, leaves
        with _capture(tmp / "listener.pcap"):
            got = subprocess.run(["/usr/bin/python3", str(tmp / "listener.py"), str(args.messages)], env=ros_env,
                                 capture_output=True, text=True, timeout=120, check=False)
            time.sleep(1.0)
    finally:
        if launch is not None:
            launch.terminate()
            launch.wait(30)
        master.terminate()
        master.wait(10)
    received = int(got.stdout.strip() or 0)
    phases: Counter[str] = Counter()
    phases["hetros talker registration (master API)"] = sum(
        1 for source, destination, _, _ in segments(tmp / "talker.pcap") if port in (source, destination))
    header_done: dict[int, int] = {}
    for source, destination, _flags, payload in segments(tmp / "listener.pcap"):
        ports = {source, destination}
        if port in ports:
            phases["rospy listener registration (master API)"] += 1
        elif talker_slave in ports:
            phases["requestTopic (slave API)"] += 1
        elif talker_tcpros in ports:
            client = destination if source == talker_tcpros else source
            state = header_done.get(client, 0)
            if state < 2:
                phases["TCPROS header exchange"] += 1
                if payload and source != talker_tcpros:
                    header_done[client] = 1  # the listener's header went
                elif payload and source == talker_tcpros and state == 1:
                    header_done[client] = 2  # the talker answered: data follow
            else:
                phases["data"] += 1
    print(f"one hetros talker -> rospy listener session, {received} messages received\n")
    print("| phase | packets |")
    print("|---|---|")
    for phase in ("hetros talker registration (master API)", "rospy listener registration (master API)",
                  "requestTopic (slave API)", "TCPROS header exchange", "data"):
        print(f"| {phase} | {phases[phase]} |")
    if received:
        print(f"| data per message (includes the connection's closing) | {phases['data'] / received:.2f} |")
    print("\n(the data rows include the ACKs and the connection's closing; the listener's registration includes"
          " rospy's own /rosout and parameter calls and its unregistration)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
