"""Examples and failure handling, run through the real CLI with real processes."""

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
SHM = Path("/dev/shm")


def hetros(*args: str, timeout: float = 90) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "hetros", *args], capture_output=True, text=True,
                          timeout=timeout, check=False)


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:
        state = Path(f"/proc/{pid}/stat").read_text().split()[2]
    except OSError:
        return False
    return state != "Z"


def worker_pids(text: str) -> dict[str, int]:
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"target (\S+) ready \(pid (\d+)", text)}


def session_segments(launcher_pid: int) -> list[str]:
    return [p.name for p in SHM.glob(f"hetros-{launcher_pid}x*")]


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_talker_listener(project: str) -> None:
    result = hetros("launch", str(EXAMPLES / "talker_listener" / project), "--duration", "2.5")
    assert result.returncode == 0, result.stderr
    for listener in ("listener", "listener2"):
        heard = re.findall(rf"\[INFO\] \[{listener}\]: I heard: \[hello world (\d+)\]", result.stderr)
        numbers = [int(n) for n in heard]
        assert len(numbers) >= 10, result.stderr
        assert numbers == list(range(numbers[0], numbers[0] + len(numbers))), "in order, none lost"
        assert numbers[0] == 0, "the start barrier lets the first message reach every listener"


@pytest.mark.parametrize("project", ["project.yaml", "project_threads.yaml"])
def test_add_two_ints(project: str) -> None:
    result = hetros("launch", str(EXAMPLES / "add_two_ints" / project), "--duration", "3")
    assert result.returncode == 0, result.stderr
    sums = re.findall(r"\[client\]: Result of add_two_ints: (\d+) \+ (\d+) = (\d+)", result.stderr)
    assert [(int(a), int(b), int(c)) for a, b, c in sums] == [(i, 10 * i, 11 * i) for i in range(5)]
    assert result.stderr.count("[server]: Incoming request") == 5


FAILING = textwrap.dedent('''
    from pathlib import Path
    from hetros.interfaces.std_msgs.msg import String

    def ticker(node):
        pub = node.create_publisher(String, "/t")
        for i in node.rate(50):
            pub.publish(String(data=str(i)))

    def crasher(node):
        seen = []
        def on_message(msg):
            seen.append(msg.data)
            if len(seen) == 5:
                raise ValueError("boom after five messages")
        node.create_subscription(String, "/t", on_message)

    def flaky(node):
        marker = Path(node.get_parameter("marker"))
        if not marker.exists():
            marker.write_text("failed once")
            raise RuntimeError("first start fails")
        node.log.info("second start works")
        node.create_subscription(String, "/t", lambda m: None)

    def wrong_value(node):
        pub = node.create_publisher(String, "/t")
        node.sleep(0.2)
        pub.publish(String(data=5))

    def counter(node):
        pub = node.create_publisher(String, "/t")
        for i in range(60):
            pub.publish(String(data=str(i)))
            node.sleep(0.01)

    def resumer(node):
        marker = Path(node.get_parameter("marker"))
        record = marker.with_suffix(".log")
        def on_message(msg):
            with record.open("a") as out:
                out.write(msg.data + "\\n")
            if msg.data == "20" and not marker.exists():
                marker.write_text("failed once")
                raise RuntimeError("fails once on message 20")
        node.create_subscription(String, "/t", on_message)
''')


def failing_project(tmp_path: Path, kind: str, consumer: str = "crasher", restart: str = "never",
                    producer: str = "ticker") -> Path:
    (tmp_path / "failing.py").write_text(FAILING)
    path = tmp_path / "project.yaml"
    path.write_text(textwrap.dedent(f"""
        name: failing
        targets: {{a: {{kind: {kind}}}, b: {{kind: {kind}}}}}
        nodes:
          ticker: {{run: failing:{producer}, target: a, publish: {{/t: std_msgs/msg/String}}}}
          {consumer}: {{run: failing:{consumer}, target: b, subscribe: {{/t: std_msgs/msg/String}},
                     restart: {restart}, parameters: {{marker: {tmp_path / 'marker'}}}}}
    """))
    return path


@pytest.mark.parametrize("kind", ["process", "thread"])
def test_node_that_raises_is_reported_once_and_stops_the_graph(tmp_path: Path, kind: str) -> None:
    start = time.monotonic()
    result = hetros("launch", str(failing_project(tmp_path, kind)), "--duration", "30")
    assert result.returncode != 0
    assert time.monotonic() - start < 20, "the failure must stop the graph, not the duration"
    assert result.stderr.count("ValueError: boom after five messages") == 1, result.stderr
    assert "node crasher (target b) raised" in result.stderr
    assert "Traceback" in result.stderr


@pytest.mark.parametrize("kind", ["process", "thread"])
def test_restart_on_failure(tmp_path: Path, kind: str) -> None:
    result = hetros("launch", str(failing_project(tmp_path, kind, "flaky", "on-failure")), "--duration", "3")
    assert result.returncode == 0, result.stderr
    assert "RuntimeError: first start fails" in result.stderr
    assert "restarting it" in result.stderr
    assert "[flaky]: second start works" in result.stderr


@pytest.mark.parametrize("kind", ["process", "thread"])
def test_restarted_subscriber_resumes_its_reliable_queue(tmp_path: Path, kind: str) -> None:
    """Messages published while a subscriber restarts wait in its FIFO: none is lost."""
    project = failing_project(tmp_path, kind, "resumer", "on-failure", producer="counter")
    result = hetros("launch", str(project), "--duration", "6")
    assert result.returncode == 0, result.stderr
    assert "RuntimeError: fails once on message 20" in result.stderr
    received = (tmp_path / "marker.log").read_text().split()
    assert received == [str(i) for i in range(60)], received


@pytest.mark.parametrize("kind", ["process", "thread"])
def test_a_wrong_field_value_is_refused_at_publish_in_every_mapping(tmp_path: Path, kind: str) -> None:
    project = failing_project(tmp_path, kind, "resumer", producer="wrong_value")
    result = hetros("launch", str(project), "--duration", "5")
    assert result.returncode == 1, result.stderr
    assert "FieldValueError: String.data must be a str, not 5 (int)" in result.stderr
    assert "node ticker (target a) raised" in result.stderr
    assert not (tmp_path / "marker.log").exists(), "nothing reached the subscriber"


def start_launcher(project: Path) -> tuple[subprocess.Popen[str], dict[str, int], str]:
    proc = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    seen = ""
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        seen += line
        if "I heard" in line:
            break
    pids = worker_pids(seen)
    assert len(pids) == 2, seen
    return proc, pids, seen


@pytest.mark.machine_wide  # compares all of /dev/shm before and after
def test_sigkill_of_a_worker_is_detected_and_reported(tmp_path: Path) -> None:
    before = set(os.listdir(SHM))
    proc, pids, _ = start_launcher(EXAMPLES / "talker_listener" / "project.yaml")
    killed_at = time.monotonic()
    os.kill(pids["cluster2"], signal.SIGKILL)
    _out, err = proc.communicate(timeout=30)
    assert proc.returncode != 0
    assert "target cluster2" in err and "died: killed by SIGKILL" in err, err
    detected = time.monotonic() - killed_at
    assert detected < 10
    for pid in pids.values():
        assert not alive(pid)
    assert session_segments(proc.pid) == []
    assert set(os.listdir(SHM)) - before == set(), "the killed worker's shared memory is reclaimed"
    again = hetros("launch", str(EXAMPLES / "talker_listener" / "project.yaml"), "--duration", "1")
    assert again.returncode == 0 and "I heard" in again.stderr, again.stderr


def test_ctrl_c_shuts_down_in_order_and_leaves_nothing(tmp_path: Path) -> None:
    proc, pids, _ = start_launcher(EXAMPLES / "talker_listener" / "project.yaml")
    os.kill(proc.pid, signal.SIGINT)
    _out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    for pid in pids.values():
        assert not alive(pid), "no stray worker process"
    assert session_segments(proc.pid) == [], "no shared-memory segment left"
    assert "did not stop" not in err


def test_process_targets_are_pinned_to_their_cpus(tmp_path: Path) -> None:
    src = (EXAMPLES / "talker_listener" / "nodes.py").read_text()
    (tmp_path / "nodes.py").write_text(src)
    project = tmp_path / "project.yaml"
    project.write_text(textwrap.dedent("""
        name: pinned
        targets: {c0: {kind: process, cpus: [0]}, c1: {kind: process, cpus: [1]}}
        nodes:
          talker:   {run: nodes:talker, target: c0, publish: {/chatter: std_msgs/msg/String}}
          listener: {run: nodes:listener, target: c1, subscribe: {/chatter: std_msgs/msg/String}}
    """))
    if (os.cpu_count() or 1) < 2:
        pytest.skip("needs two CPUs")
    result = hetros("launch", str(project), "--duration", "1")
    assert result.returncode == 0, result.stderr
    assert "target c0 ready" in result.stderr and "cpus [0])" in result.stderr
    assert "cpus [1])" in result.stderr
    assert "[listener]: I heard" in result.stderr


def test_launcher_killed_leaves_no_worker_traceback_or_file(tmp_path: Path) -> None:
    plans_before = set(Path(os.environ.get("TMPDIR", "/tmp")).glob("hetros-plan-*.json"))
    proc = subprocess.Popen([sys.executable, "-m", "hetros", "launch",
                             str(EXAMPLES / "talker_listener" / "project.yaml")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stderr is not None
    seen = ""
    while "I heard" not in seen:
        seen += proc.stderr.readline()
    pids = worker_pids(seen)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    deadline = time.monotonic() + 15
    while any(alive(pid) for pid in pids.values()) and time.monotonic() < deadline:
        time.sleep(0.1)
    rest = proc.stderr.read()
    assert not any(alive(pid) for pid in pids.values()), "workers stop when their launcher dies"
    assert "Traceback" not in rest and "BrokenPipeError" not in rest, rest
    assert "the launcher is gone" in rest
    assert session_segments(proc.pid) == [], "the credits files of the session are removed"
    assert set(Path(os.environ.get("TMPDIR", "/tmp")).glob("hetros-plan-*.json")) <= plans_before


SLOW_START = textwrap.dedent('''
    import sys, time
    if sys.argv[0] != "-c":   # not `hetros check`'s import probe: a worker or the launcher
        time.sleep(3.0)       # a node module that takes a while to import

    def idle(node):
        node.spin()
''')


def _workers_of(launcher: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                cmdline = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            if b"hetros.launch.launcher._worker" in cmdline and f"{launcher}x".encode() in cmdline:
                found.append(int(entry.name))
    return found


def test_ctrl_c_during_start_up_is_clean(tmp_path: Path) -> None:
    """Ctrl-C while targets are still starting: no traceback, no stray process, exit 130."""
    (tmp_path / "slow.py").write_text(SLOW_START)
    project = tmp_path / "project.yaml"
    project.write_text(textwrap.dedent("""
        name: slow
        targets: {a: {kind: process}, main: {kind: thread}}
        nodes:
          far: {run: slow:idle, target: a}
          near: {run: slow:idle, target: main}
    """))
    proc = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not _workers_of(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    workers = _workers_of(proc.pid)
    assert workers, "the worker never started"
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    _out, err = proc.communicate(timeout=60)
    assert "Traceback" not in err and "cannot join thread" not in err, err
    assert proc.returncode == 130, err
    for pid in workers:
        assert not alive(pid), "no stray worker"


STUBBORN = textwrap.dedent('''
    import time

    def stubborn(node):
        while True:          # ignores shutdown on purpose
            time.sleep(0.1)
''')


def test_a_target_that_had_to_be_killed_fails_the_launch(tmp_path: Path) -> None:
    (tmp_path / "stubborn.py").write_text(STUBBORN)
    project = tmp_path / "project.yaml"
    project.write_text(textwrap.dedent("""
        name: stubborn
        targets: {a: {kind: process}}
        nodes:
          stubborn: {run: stubborn:stubborn, target: a}
    """))
    result = hetros("launch", str(project), "--duration", "1", timeout=60)
    assert result.returncode == 1, result.stderr
    assert "did not stop within 5 s" in result.stderr


def test_the_start_up_limit_is_a_setting_and_named_when_missed(tmp_path: Path) -> None:
    """A target whose module takes 3 s to import misses a 1 s limit, with the flag that sets it named; a
    bad value is refused by the command line."""
    (tmp_path / "slow.py").write_text("import time\ntime.sleep(3)\n\ndef node(node):\n    pass\n")
    (tmp_path / "project.yaml").write_text("name: slow\ntargets: {a: {kind: process}}\n"
                                           "nodes:\n  n: {run: slow:node, target: a}\n")
    command = [sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--start-timeout"]
    missed = subprocess.run([*command, "1"], capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)
    assert missed.returncode != 0
    assert "did not start within 1 s (the start-up limit: hetros launch --start-timeout)" in missed.stderr
    fine = subprocess.run([*command, "30"], capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)
    assert fine.returncode == 0, fine.stderr
    refused = subprocess.run([*command, "nan"], capture_output=True, text=True, timeout=60, check=False, cwd=tmp_path)
    assert refused.returncode == 2 and "must be a positive number of seconds, not 'nan'" in refused.stderr
