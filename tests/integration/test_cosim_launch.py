"""Mixed graphs under ``hetros launch``: software nodes and hardware nodes co-simulated in Verilator,
the same results as the software mapping, nothing lost under back-pressure, failures reported."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytest.importorskip("amaranth")
pytestmark = [pytest.mark.rtl,
              pytest.mark.skipif(shutil.which("verilator") is None, reason="Debian's verilator is not installed")]

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def launch(project: Path, cwd: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "120", *extra],
                          capture_output=True, text=True, timeout=240, check=False, cwd=cwd)


@pytest.mark.parametrize(("mappings", "out"), [
    (("project.yaml", "project_fpga.yaml", "project_board.yaml"), "sobel_hw"),
    (("project_chain.yaml", "project_chain_fpga.yaml", "project_chain_sequential.yaml"), "sobel_chain"),
])
def test_filters_on_fpga_targets_give_the_software_mappings_pixels(tmp_path: Path, mappings: tuple[str, ...],
                                                                    out: str) -> None:
    """Sobel alone (in software, co-simulated, and on a board through PYNQ's surface with the simulator
    behind it), and blur -> Sobel in software, as dataflow (one target) and sequential (two)."""
    results = {}
    for mapping in mappings:
        cwd = tmp_path / mapping
        cwd.mkdir()
        result = launch(EXAMPLES / "sobel_hw" / mapping, cwd)
        assert result.returncode == 0, result.stderr
        assert "8 frames, every pixel equal to the software filters" in result.stderr
        if "board" in mapping:  # each image one DMA transfer in, one out: the path a ZCU104 takes
            assert "on board zcu104 through SimulatedOverlay (2 DMA channels)" in result.stderr
        results[mapping] = (cwd / "out" / out / "edges.txt").read_text()
    assert len(set(results.values())) == 1
    assert len(results[mappings[0]].splitlines()) == 8


def test_the_vehicle_with_compensation_and_blur_in_hardware_sees_what_software_sees(tmp_path: Path) -> None:
    """examples/lane_following: the fpga mapping's lane centres, frame by frame, and stop frames are the
    software mapping's (the image stages are bit-exact, so everything after them is too)."""
    import json

    import yaml

    example = EXAMPLES / "lane_following"
    summaries = {}
    for project in ("project.yaml", "project_fpga.yaml"):
        data = yaml.safe_load((example / project).read_text())
        data["messages"] = [str((example / m).resolve()) for m in data["messages"]]
        data["nodes"]["camera"]["parameters"]["frames"] = 40
        data["nodes"]["monitor"]["parameters"].update({"frames": 40, "out": str(tmp_path / project)})
        variant = tmp_path / f"variant_{project}"
        variant.write_text(yaml.safe_dump(data))
        result = subprocess.run([sys.executable, "-m", "hetros", "launch", str(variant), "--duration", "200"],
                                capture_output=True, text=True, timeout=240, check=False, cwd=tmp_path,
                                env=dict(os.environ, PYTHONPATH=str(example)))
        assert result.returncode == 0, result.stderr
        summaries[project] = json.loads((tmp_path / project / "summary.json").read_text())
    software, hardware = summaries["project.yaml"], summaries["project_fpga.yaml"]
    assert len(software["centres"]) == 40 and software["centres"] == hardware["centres"]
    assert software["stopped"] == hardware["stopped"] == list(range(20, 35))


def test_the_fpga_mapping_reports_simulated_time_beside_wall_time(tmp_path: Path) -> None:
    result = launch(EXAMPLES / "sobel_hw" / "project_fpga.yaml", tmp_path)
    assert result.returncode == 0, result.stderr
    assert re.search(r"fpga target fpga: \d+ cycles simulated \([\d.]+ ms at 100 MHz\) in [\d.]+ s of simulation",
                     result.stderr)
    # a 64x48 image is 3072 pixels: the Sobel takes a cycle a pixel, its header a few more
    per_message = re.search(r"sobel -> software on /image_edges .*: 8 messages, \d+ beats, (\d+) cycles per message "
                            r"\(([\d.]+) µs at 100 MHz\)", result.stderr)
    assert per_message is not None, result.stderr
    assert 3072 <= int(per_message.group(1)) < 3300


@pytest.mark.parametrize("project", ["project_fpga.yaml", "project_fpga_verilog.yaml"])
def test_ping_pong_with_the_copy_node_in_hardware_returns_every_byte(tmp_path: Path, project: str) -> None:
    """The copy node as Amaranth (hetros.hw.nodes.Echo) and as Verilog in Vitis HLS's shape."""
    result = launch(EXAMPLES / "ping_pong" / project, tmp_path)
    assert result.returncode == 0, result.stderr
    sizes = [int(s) for s in re.findall(r"\[ping\]: round trip +(\d+) B:", result.stderr)]
    assert sizes == [4, 8192, 1 << 20]


def test_amaranths_simulator_serves_a_launch_too(tmp_path: Path) -> None:
    """sim: amaranth, no compiler: the adder answers as in Verilator (small designs only: it is slow)."""
    project = tmp_path / "project_fpga.yaml"
    text = (EXAMPLES / "add_two_ints" / "project_fpga.yaml").read_text()
    project.write_text(text.replace("part: xczu7ev-ffvc1156-2-e}", "part: xczu7ev-ffvc1156-2-e, sim: amaranth}"))
    shutil.copy(EXAMPLES / "add_two_ints" / "nodes.py", tmp_path / "nodes.py")
    result = launch(project, tmp_path)
    assert result.returncode == 0, result.stderr
    assert "fpga target fpga in amaranth" in result.stderr
    assert re.findall(r"Result of add_two_ints: (.*)", result.stderr) == [f"{i} + {10 * i} = {11 * i}"
                                                                          for i in range(5)]


def test_sorting_with_the_sorter_in_hardware_matches_numpy(tmp_path: Path) -> None:
    result = launch(EXAMPLES / "sorting" / "project_fpga.yaml", tmp_path)
    assert result.returncode == 0, result.stderr
    assert len(re.findall(r"run \d: 2048 numbers sorted correctly", result.stderr)) == 5


def test_add_two_ints_served_by_hardware_answers_as_the_software_server(tmp_path: Path) -> None:
    answers = {}
    for mapping in ("project.yaml", "project_fpga.yaml"):
        result = launch(EXAMPLES / "add_two_ints" / mapping, tmp_path, )
        answers[mapping] = re.findall(r"Result of add_two_ints: (.*)", result.stderr)
    assert answers["project.yaml"] == answers["project_fpga.yaml"]
    assert answers["project.yaml"] == [f"{i} + {10 * i} = {11 * i}" for i in range(5)]


NODES = '''
import time

from hetros import Node
from hetros.interfaces.std_msgs.msg import UInt8MultiArray


def source(node: Node) -> None:
    pub = node.create_publisher(UInt8MultiArray, "/a")
    fail_after = node.get_parameter("fail_after", -1)
    for seq in range(node.get_parameter("count")):
        if seq == fail_after:
            raise ValueError("the source broke on purpose")
        message = UInt8MultiArray(data=bytes([seq % 256]) * (1 + seq % 300))
        message.layout.data_offset = seq
        pub.publish(message)
        time.sleep(node.get_parameter("pause", 0.0))


def latest_sink(node: Node) -> None:
    """Slow, on keep_last topics: takes what is newest until the last message arrives."""
    sub = node.create_subscription(UInt8MultiArray, "/b")
    count, seen = node.get_parameter("count"), []
    while not seen or seen[-1] != count - 1:
        seen.append(sub.take().layout.data_offset)
        time.sleep(0.01)
    if seen != sorted(set(seen)):
        raise ValueError(f"out of order or repeated: {seen}")
    node.log.info("%d of %d messages, newest last", len(seen), count)


def echo(node: Node) -> None:
    pub = node.create_publisher(UInt8MultiArray, "/b")
    for message in node.create_subscription(UInt8MultiArray, "/a"):
        pub.publish(message)


def sink(node: Node) -> None:
    sub = node.create_subscription(UInt8MultiArray, "/b")
    count = node.get_parameter("count")
    for seq in range(count):
        message = sub.take()
        if message.layout.data_offset != seq or bytes(message.data) != bytes([seq % 256]) * (1 + seq % 300):
            raise ValueError(f"message {seq} arrived as {message.layout.data_offset}")
        time.sleep(node.get_parameter("pause", 0.0))
    node.log.info("%d messages through the hardware, in order and intact", count)
'''


def _echo_project(tmp_path: Path, source: str = "", sink: str = "", topics: str = "") -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    path = tmp_path / "project.yaml"
    path.write_text(textwrap.dedent(f"""\
        name: echo
        targets:
          io: {{kind: process}}
          fpga: {{kind: fpga, data_width: 32}}
        nodes:
          source: {{run: nodes:source, target: io, parameters: {{count: 300{source}}},
                   publish: {{/a: std_msgs/msg/UInt8MultiArray}}}}
          echo: {{run: nodes:echo, hw: "hetros.hw.nodes:Echo", target: fpga, parameters: {{source: /a, sink: /b}},
                 subscribe: {{/a: std_msgs/msg/UInt8MultiArray}}, publish: {{/b: std_msgs/msg/UInt8MultiArray}}}}
          sink: {{run: nodes:sink, target: io, required: true, parameters: {{count: 300{sink}}},
                 subscribe: {{/b: std_msgs/msg/UInt8MultiArray}}}}
        topics:
          /a: {{depth: 2}}
          /b: {{depth: 2}}
        {topics}"""))
    return path


def test_a_reliable_topic_through_a_gateway_loses_nothing_under_back_pressure(tmp_path: Path) -> None:
    """A fast publisher, a slow subscriber, depth 2 on both sides: the gateway and the hardware hold,
    the publisher blocks, and every message arrives in order."""
    result = launch(_echo_project(tmp_path, sink=", pause: 0.003"), tmp_path)
    assert result.returncode == 0, result.stderr
    assert "300 messages through the hardware, in order and intact" in result.stderr


def test_keep_last_across_a_gateway_drops_the_oldest_and_delivers_the_newest(tmp_path: Path) -> None:
    path = _echo_project(tmp_path, topics="")
    text = path.read_text().replace("run: nodes:sink,", "run: nodes:latest_sink,")
    text = text.replace("/a: {depth: 2}", "/a: {history: keep_last, depth: 1}").replace(
        "/b: {depth: 2}", "/b: {history: keep_last, depth: 1}")
    path.write_text(text)
    result = launch(path, tmp_path)
    assert result.returncode == 0, result.stderr
    kept = re.search(r"(\d+) of 300 messages, newest last", result.stderr)
    assert kept is not None, result.stderr
    assert int(kept.group(1)) < 300, "a slow keep_last subscriber behind the hardware should have lost some"


def test_a_software_nodes_crash_stops_the_graph_and_the_simulator(tmp_path: Path) -> None:
    started = time.monotonic()
    result = launch(_echo_project(tmp_path, source=", fail_after: 20"), tmp_path)
    assert result.returncode != 0
    assert "the source broke on purpose" in result.stderr
    assert time.monotonic() - started < 60, "the simulator kept the graph from stopping"
    assert re.search(r"fpga target fpga: \d+ cycles simulated", result.stderr), "the simulator did not stop in order"


def test_the_simulator_process_dying_is_reported_like_any_target(tmp_path: Path) -> None:
    project = _echo_project(tmp_path, source=", pause: 0.05", sink=", pause: 0.0")
    with subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "60"],
                          stderr=subprocess.PIPE, text=True, cwd=tmp_path) as proc:
        assert proc.stderr is not None
        lines = []
        pid = None
        for line in proc.stderr:
            lines.append(line)
            found = re.search(r"target fpga ready \(pid (\d+)", line)
            if found:
                pid = int(found.group(1))
            if pid is not None and "in verilator (" in line:
                break
        assert pid is not None, "".join(lines)
        time.sleep(0.5)
        os.kill(pid, signal.SIGKILL)
        rest = proc.stderr.read()
        code = proc.wait(60)
    assert code != 0
    assert re.search(r"target fpga died", rest), rest
