"""Faults a user's machine brings: a stopped and continued worker, exceptions at shutdown."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def _ready_pids(proc: subprocess.Popen[str], count: int) -> tuple[dict[str, int], list[str]]:
    lines: list[str] = []
    assert proc.stdout is not None
    pids: dict[str, int] = {}
    while len(pids) < count:
        line = proc.stdout.readline()
        assert line, "".join(lines)
        lines.append(line)
        if match := re.search(r"target (\S+) ready \(pid (\d+)", line):
            pids[match.group(1)] = int(match.group(2))
    return pids, lines


@pytest.mark.timeout(120)
def test_a_worker_stopped_and_continued_goes_on(tmp_path: Path) -> None:
    """SIGSTOP then SIGCONT (a debugger, a suspended laptop) interrupts iceoryx2's waits: they
    are retried, and the graph goes on (it used to stop with "failed: InterruptSignal")."""
    proc = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(EXAMPLES / "talker_listener/project.yaml"),
                             "--duration", "8"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    pids, lines = _ready_pids(proc, 2)
    time.sleep(1.5)
    for _ in range(4):
        for pid in pids.values():
            os.kill(pid, signal.SIGSTOP)
        time.sleep(0.3)
        for pid in pids.values():
            os.kill(pid, signal.SIGCONT)
        time.sleep(0.3)
    output, _ = proc.communicate(timeout=60)
    output = "".join(lines) + output
    assert proc.returncode == 0, output[-3000:]
    assert "InterruptSignal" not in output and "[ERROR]" not in output, output[-3000:]
    heard = [int(n) for n in re.findall(r"\[listener2\]: I heard: \[hello world (\d+)\]", output)]
    assert heard and heard == list(range(heard[0], heard[0] + len(heard))), "listener2 lost messages"
    assert heard[-1] > 40, f"the graph did not go on after the signals (last heard: {heard[-1]})"


AFTER_LOOP = textwrap.dedent('''
    from hetros import Node
    from hetros.interfaces.std_msgs.msg import Int32


    def looper(node: Node) -> None:
        pub = node.create_publisher(Int32, "/n")
        for i in node.rate(50.0):
            pub.publish(Int32(data=i))
        node.log.info("after the loop")
        raise ValueError("the summary after the loop is wrong")


    def reader(node: Node) -> None:
        sub = node.create_subscription(Int32, "/n")
        for _ in node.rate(50.0):
            sub.try_take()
        node.log.info("reader summary: done")
''')


@pytest.mark.parametrize("mapping", ["thread", "process"])
def test_an_exception_after_shutdown_is_reported_and_sets_the_exit_code(tmp_path: Path, mapping: str) -> None:
    (tmp_path / "after.py").write_text(AFTER_LOOP)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: after
        targets: {{a: {{kind: {mapping}}}, b: {{kind: {mapping}}}}}
        nodes:
          looper: {{run: "after:looper", target: a, publish: {{/n: std_msgs/msg/Int32}}}}
          reader: {{run: "after:reader", target: b, subscribe: {{/n: std_msgs/msg/Int32}}}}
    """))
    proc = subprocess.run([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration", "2"],
                          capture_output=True, text=True, timeout=60)
    assert "after the loop" in proc.stderr and "reader summary: done" in proc.stderr, proc.stderr[-3000:]
    assert "ValueError: the summary after the loop is wrong" in proc.stderr, proc.stderr[-3000:]
    assert "node looper" in proc.stderr and "raised during shutdown" in proc.stderr, proc.stderr[-3000:]
    assert proc.returncode == 1, proc.stderr[-3000:]


NO_MASTER_NODES = textwrap.dedent('''
    from hetros import Node
    from hetros.interfaces.std_msgs.msg import String


    def talk(node: Node) -> None:
        pub = node.create_publisher(String, "/x")
        for i in node.rate(5.0):
            pub.publish(String(data=str(i)))
''')


@pytest.mark.timeout(60)
def test_a_ros1_target_without_a_master_says_what_to_start_and_duration_holds(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(NO_MASTER_NODES)
    (tmp_path / "project.yaml").write_text(textwrap.dedent("""
        name: nomaster
        targets: {legacy: {kind: ros1}}
        external: {ros1: {master: "http://127.0.0.1:1"}}
        nodes:
          talker: {run: nodes:talk, target: legacy, publish: {/x: std_msgs/msg/String}}
    """))
    started = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration", "3"],
                          capture_output=True, text=True, timeout=50)
    assert time.monotonic() - started < 12, f"--duration 3 did not hold:\n{proc.stderr[-3000:]}"
    assert "start `hetros master` or roscore" in proc.stderr, proc.stderr[-3000:]
    assert "did not stop within" not in proc.stderr, proc.stderr[-3000:]
    assert proc.returncode == 1, proc.stderr[-3000:]


def _address_space_200_mb() -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (200 << 20, 200 << 20))


@pytest.mark.timeout(60)
def test_a_launch_out_of_memory_ends_with_an_error_not_a_traceback(tmp_path: Path) -> None:
    """Under a 200 MB address-space limit the launcher cannot start its threads: it says so
    and what to raise (it used to end in an unhandled "can't start new thread" traceback)."""
    proc = subprocess.run([sys.executable, "-m", "hetros", "launch", str(EXAMPLES / "talker_listener/project.yaml"),
                           "--duration", "3"], capture_output=True, text=True, timeout=50,
                          preexec_fn=_address_space_200_mb)
    assert proc.returncode == 1, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert "ran out of resources" in proc.stderr, proc.stderr[-3000:]


REQUIRED_CONSUMER = textwrap.dedent('''
    from hetros import Node, TakeTimeoutError
    from hetros.interfaces.std_msgs.msg import Int32


    def silent(node: Node) -> None:
        node.create_publisher(Int32, "/n")  # declared, never publishes: a sensor that never came up
        node.spin()


    def talker(node: Node) -> None:
        pub = node.create_publisher(Int32, "/n")
        for i in node.rate(20.0):
            pub.publish(Int32(data=i))


    def taking(node: Node) -> None:
        sub = node.create_subscription(Int32, "/n")
        for _ in range(3):
            try:
                sub.take(timeout=0.5)
            except TakeTimeoutError:
                node.log.info("no frame")


    def polling(node: Node) -> None:
        sub = node.create_subscription(Int32, "/n")
        for tick in node.rate(10.0):
            if sub.try_take() is not None or tick == 15:
                return


    def called(node: Node) -> None:
        node.create_subscription(Int32, "/n", lambda message: None)
        node.spin(timeout=1.5)
''')


@pytest.mark.timeout(120)
@pytest.mark.parametrize("consumer", ["taking", "polling", "called"])
def test_a_required_consumer_that_heard_nothing_fails_the_launch(tmp_path: Path, consumer: str) -> None:
    """A required display that got no frame ended the launch with 0, as if it had shown every one."""
    (tmp_path / "nodes.py").write_text(REQUIRED_CONSUMER)
    for producer in ("silent", "talker"):
        (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
            name: required
            targets: {{a: {{kind: process}}, b: {{kind: process}}}}
            nodes:
              producer: {{run: "nodes:{producer}", target: a, publish: {{/n: std_msgs/msg/Int32}}}}
              display: {{run: "nodes:{consumer}", target: b, required: true, subscribe: {{/n: std_msgs/msg/Int32}}}}
        """))
        proc = subprocess.run([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"),
                               "--duration", "30"], capture_output=True, text=True, timeout=90)
        if producer == "silent":
            assert proc.returncode == 1, proc.stderr[-3000:]
            assert "required node display finished without receiving a message on /n" in proc.stderr, \
                proc.stderr[-3000:]
        else:
            assert proc.returncode == 0, proc.stderr[-3000:]
            assert "required node display finished;" in proc.stderr or "display finished" in proc.stderr
