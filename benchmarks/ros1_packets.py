"""Packets of a ROS 1 publisher -> rospy session over loopback, by phase, as the hardware-TCPROS paper counted
them, for a software publisher and for the fpga target's hardware TCPROS side by side.

    sudo .venv/bin/python benchmarks/ros1_packets.py [--messages 10] [--out out/bench/ros1_packets]

Runs `hetros master`, then per publisher: ``software``, a hetros talker on a `kind: ros1` target
(TCPROS framed by Python); ``hardware``, a talker feeding a co-simulated hardware node whose
/chatter the fpga target frames in RTL (its gateway registers, ``examples/hw_tcpros``); and a
stock rospy listener that takes ``--messages`` messages, while tcpdump records loopback. Every TCP segment
(handshake, data, ACK, FIN) is put in one phase by its ports: registration (anything to or
from the master), requestTopic (the listener calling the talker's slave API), the TCPROS
header exchange (the talker's data connection up to and including the talker's header),
and the data phase (the rest of that connection, reported per message). Prints a table, writes
``packets.json`` and ``packets.png``. Needs root (tcpdump) and Debian's rospy.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
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
        pub = node.create_publisher(String, node.get_parameter("topic", "/chatter"))
        for i in node.rate(20):
            pub.publish(String(data=f"hello {i}"))

    def echo(node):
        pub = node.create_publisher(String, "/chatter")
        node.create_subscription(String, "/words", pub.publish)
        node.spin()
''')
PROJECTS = {
    "software": """
        name: packets
        targets: {{ros1: {{kind: ros1}}}}
        nodes:
          talker: {{run: nodes:talker, target: ros1, publish: {{/chatter: std_msgs/msg/String}}}}
        external:
          ros1: {{master: '{uri}'}}
    """,
    "hardware": """
        name: packets
        targets: {{main: {{kind: process}}, fpga: {{kind: fpga}}}}
        nodes:
          words: {{run: nodes:talker, target: main, parameters: {{topic: /words}},
                  publish: {{/words: std_msgs/msg/String}}}}
          talker: {{run: nodes:echo, hw: hetros.hw.nodes:Echo, target: fpga, parameters: {{source: /words,
                   sink: /chatter}}, subscribe: {{/words: std_msgs/msg/String}},
                   publish: {{/chatter: std_msgs/msg/String}}}}
        external:
          ros1: {{master: '{uri}', export: [/chatter]}}
    """,
}
# the ROS 1 node that publishes /chatter in each run
PUBLISHER_NODE = {"software": "/talker", "hardware": "/packets_fpga"}
PHASES = ("publisher registration (master API)", "rospy listener registration (master API)",
          "requestTopic (slave API)", "TCPROS header exchange", "data")
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


def session(kind: str, messages: int, tmp: Path) -> tuple[Counter[str], int]:
    """One publisher of ``kind`` and a rospy listener: packets by phase, and the messages received."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    env = dict(os.environ, ROS_MASTER_URI=uri, ROS_HOSTNAME="127.0.0.1", ROS_HOME=str(tmp))
    ros_env = {k: v for k, v in env.items() if k != "PYTHONPATH"}
    (tmp / "nodes.py").write_text(NODES)
    (tmp / "listener.py").write_text(LISTENER)
    (tmp / "project.yaml").write_text(textwrap.dedent(PROJECTS[kind].format(uri=uri)))
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
        if kind == "hardware":  # once before: Verilator's build is then cached, and the start takes a second
            subprocess.run([sys.executable, "-m", "hetros", "launch", str(tmp / "project.yaml"), "--duration", "3"],
                           cwd=tmp, env=env, capture_output=True, timeout=600, check=False)
        # capture 1: the publisher starts and registers (nobody else talks meanwhile)
        with _capture(tmp / f"{kind}-talker.pcap"):
            launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp / "project.yaml")],
                                      cwd=tmp, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            time.sleep(6.0)
        code, _, api = xmlrpc.client.ServerProxy(uri).lookupNode("/packets", PUBLISHER_NODE[kind])
        if code != 1:
            raise SystemExit(f"the {kind} publisher {PUBLISHER_NODE[kind]} did not register within 6 s")
        talker_api = str(api)
        talker_slave = int(talker_api.rstrip("/").rsplit(":", 1)[1])
        talker_tcpros = int(xmlrpc.client.ServerProxy(talker_api).requestTopic(
            "/packets", "/chatter", [["TCPROS"]])[2][2])
        # capture 2: a stock rospy listener joins, takes the messages, leaves
        with _capture(tmp / f"{kind}-listener.pcap"):
            got = subprocess.run(["/usr/bin/python3", str(tmp / "listener.py"), str(messages)], env=ros_env,
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
    phases[PHASES[0]] = sum(1 for source, destination, _, _ in segments(tmp / f"{kind}-talker.pcap")
                            if port in (source, destination))
    header_done: dict[int, int] = {}
    for source, destination, _flags, payload in segments(tmp / f"{kind}-listener.pcap"):
        ports = {source, destination}
        if port in ports:
            phases[PHASES[1]] += 1
        elif talker_slave in ports:
            phases[PHASES[2]] += 1
        elif talker_tcpros in ports:
            client = destination if source == talker_tcpros else source
            state = header_done.get(client, 0)
            if state < 2:
                phases[PHASES[3]] += 1
                if payload and source != talker_tcpros:
                    header_done[client] = 1  # the listener's header went
                elif payload and source == talker_tcpros and state == 1:
                    header_done[client] = 2  # the talker answered: data follow
            else:
                phases[PHASES[4]] += 1
    return phases, received


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--messages", type=int, default=10)
    parser.add_argument("--out", type=Path, default=Path("out/bench/ros1_packets"))
    args = parser.parse_args(argv)
    if os.geteuid() != 0:
        raise SystemExit("tcpdump needs root")
    if shutil.which("tcpdump") is None:
        raise SystemExit("tcpdump is not installed: apt-get install tcpdump (Debian's), then run this again")
    tmp = Path(tempfile.mkdtemp(prefix="hetros-packets-"))
    results = {}
    for kind in PROJECTS:
        phases, received = session(kind, args.messages, tmp)
        results[kind] = {"phases": dict(phases), "received": received,
                         "data_per_message": phases["data"] / received if received else None}
    print(f"a ROS 1 publisher -> stock rospy listener, {args.messages} messages; TCP segments on loopback by phase\n")
    print("| phase | software publisher (Python TCPROS) | hardware publisher (RTL-framed, co-simulated) |")
    print("|---|---|---|")
    for phase in PHASES:
        print(f"| {phase} | {results['software']['phases'].get(phase, 0)} | "
              f"{results['hardware']['phases'].get(phase, 0)} |")
    per = [results[k]["data_per_message"] for k in PROJECTS]
    print("| data per message (includes the connection's closing) | "
          + " | ".join("-" if p is None else f"{p:.2f}" for p in per) + " |")
    print("\n(the data rows include the ACKs and the connection's closing; the listener's registration includes"
          " rospy's own /rosout and parameter calls and its unregistration)")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "packets.json").write_text(json.dumps(results, indent=1))
    _plot(results, args.out / "packets.png")
    print(f"\nwrote {args.out / 'packets.json'} and {args.out / 'packets.png'}")
    return 0


def _plot(results: dict[str, dict[str, object]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4))
    width = 0.4
    for offset, kind in ((-width / 2, "software"), (width / 2, "hardware")):
        counts = results[kind]["phases"]
        assert isinstance(counts, dict)
        ax.bar([i + offset for i in range(len(PHASES))], [counts.get(p, 0) for p in PHASES], width, label=kind)
    ax.set_xticks(range(len(PHASES)), [p.split(" (")[0] for p in PHASES], rotation=15, fontsize=8)
    ax.set_ylabel("TCP segments")
    ax.set_title("ROS 1 session by phase: software vs hardware TCPROS publisher")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    sys.exit(main())
