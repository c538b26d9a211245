"""One graph over three machines: network namespaces joined by a bridge, one host each, started
from one project file with `hetros launch --as <host>` in each. Edges between hosts go over DDS."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from hetros.project import load_project, plan
from tests.support.netns import Namespace, unavailable

pytestmark = pytest.mark.skipif(bool(unavailable()), reason=f"no network namespaces here: {unavailable()}")

NODES = textwrap.dedent('''
    from hetros.interfaces.example_interfaces.srv import AddTwoInts
    from hetros.interfaces.std_msgs.msg import String

    def source(node):
        node.create_service(AddTwoInts, "/add", lambda r: AddTwoInts.Response(sum=r.a + r.b))
        pub = node.create_publisher(String, "/a")
        count = iter(range(10**9))
        node.create_timer(0.05, lambda: pub.publish(String(data=f"m{next(count)}")))

    def relay(node):
        pub = node.create_publisher(String, "/b")
        node.create_subscription(String, "/a", lambda m: pub.publish(String(data=m.data + " via h1")))

    def sink(node):
        add = node.create_client(AddTwoInts, "/add")
        with open(node.get_parameter("out"), "a") as out:
            out.write(f"add {add.call(AddTwoInts.Request(a=40, b=2), timeout=30).sum}\\n")
            out.flush()
            for message in node.create_subscription(String, "/b"):
                out.write(message.data + "\\n")
                out.flush()
''')


def _project(folder: Path, spaces: list[Namespace], policy: str) -> Path:
    folder.mkdir(exist_ok=True)
    (folder / "nodes.py").write_text(NODES)
    hosts = "\n".join(f"  h{i}: {{address: {s.address}}}" for i, s in enumerate(spaces))
    path = folder / "project.yaml"
    path.write_text(f"""name: chain
on_peer_lost: {policy}
hosts:
{hosts}
targets:
  t0: {{kind: process, host: h0}}
  t1: {{kind: process, host: h1}}
  t2: {{kind: thread, host: h2}}
nodes:
  source: {{run: nodes:source, target: t0, publish: {{/a: std_msgs/msg/String}},
           services: {{/add: example_interfaces/srv/AddTwoInts}}}}
  relay: {{run: nodes:relay, target: t1, subscribe: {{/a: std_msgs/msg/String}}, publish: {{/b: std_msgs/msg/String}}}}
  sink: {{run: nodes:sink, target: t2, subscribe: {{/b: std_msgs/msg/String}},
         clients: {{/add: example_interfaces/srv/AddTwoInts}}, parameters: {{out: {folder / "got.txt"}}}}}
""")
    return path


class _Host:
    def __init__(self, space: Namespace, project: Path, name: str, log: Path) -> None:
        self.log = log
        self._out = log.open("a")
        self.proc = subprocess.Popen(space.command(sys.executable, "-m", "hetros", "launch", str(project),
                                                   "--as", name, "--duration", "90"),
                                     cwd=project.parent, stdout=self._out, stderr=subprocess.STDOUT, text=True)

    def text(self) -> str:
        return self.log.read_text()

    def stop(self) -> str:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._out.close()
        return self.text()


def _wait(condition: object, timeout: float, what: str, logs: list[_Host]) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():  # type: ignore[operator]
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}\n" +
                         "\n".join(f"--- {h.log.name}\n{h.text()}" for h in logs))


def test_a_chain_over_three_hosts_survives_losing_one(spaces: list[Namespace], tmp_path: Path) -> None:
    project = _project(tmp_path, spaces, "continue")
    planned = plan(load_project(project))
    assert {(e.channel, e.transport) for e in planned.edges} >= {("/a", "dds"), ("/b", "dds")}
    got = tmp_path / "got.txt"
    hosts = [_Host(space, project, f"h{i}", tmp_path / f"h{i}.log") for i, space in enumerate(spaces)]
    try:
        lines = lambda: got.read_text().splitlines() if got.exists() else []
        _wait(lambda: "add 42" in lines() and sum(" via h1" in line for line in lines()) >= 10, 60,
              "the chain's first messages and the service reply", hosts)
        delivered = [int(line[1:].split()[0]) for line in lines() if line.endswith(" via h1")]
        assert delivered == sorted(delivered) and len(set(delivered)) == len(delivered)  # in order, once

        hosts[1].proc.kill()  # the relay's host vanishes without a word
        killed = time.monotonic()
        lost = re.compile(r"host h1 \(\S+\) is gone")
        _wait(lambda: lost.search(hosts[0].text()) and lost.search(hosts[2].text()), 5,
              "h0 and h2 to report h1's loss", hosts)
        noticed = time.monotonic() - killed
        print(f"h1's loss was reported after {noticed:.2f} s")
        assert noticed < 2.5, f"h1's loss was reported after {noticed:.2f} s"
        assert hosts[0].proc.poll() is None and hosts[2].proc.poll() is None  # on_peer_lost: continue

        before = len(lines())
        hosts[1] = _Host(spaces[1], project, "h1", tmp_path / "h1-again.log")
        _wait(lambda: len(lines()) >= before + 10, 60, "traffic to resume through the restarted h1", hosts)
        assert "host h1" in hosts[0].text() and "is back" in hosts[0].text()
    finally:
        outputs = [host.stop() for host in hosts]
    sent = re.search(r"dds: sent (\d+) samples of /a to other hosts", outputs[0])
    received = re.search(r"dds: received (\d+) samples of /b from h1", outputs[2])
    assert sent and int(sent.group(1)) > 10, outputs[0]
    assert received and int(received.group(1)) >= 20, outputs[2]


def test_hosts_with_different_projects_refuse_each_other(spaces: list[Namespace], tmp_path: Path) -> None:
    first = _project(tmp_path / "a", spaces, "stop")
    second = _project(tmp_path / "b", spaces, "stop")
    second.write_text(second.read_text() + "topics: {/a: {depth: 20}}\n")
    hosts = [_Host(spaces[0], first, "h0", tmp_path / "h0.log"), _Host(spaces[1], second, "h1", tmp_path / "h1.log")]
    try:
        _wait(lambda: all(h.proc.poll() is not None for h in hosts), 60, "both hosts to refuse", hosts)
    finally:
        outputs = [host.stop() for host in hosts]
    hashes = re.compile(r"host h[01] \(\S+\) runs project chain with hash [0-9a-f]{16}, this host \(h[01]\) with "
                        r"[0-9a-f]{16}: run the same checkout")
    assert all(hashes.search(out) for out in outputs), outputs
    assert all(h.proc.returncode == 1 for h in hosts)
