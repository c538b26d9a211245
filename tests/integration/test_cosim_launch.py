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


class Waves:
    """A VCD file's signals by name, each as its (time, value) changes: what GTKWave shows."""

    def __init__(self, timescale: str, changes: dict[str, list[tuple[int, str]]], start: int, end: int) -> None:
        self.timescale, self.changes, self.start, self.end = timescale, changes, start, end

    def values(self, name: str) -> list[tuple[int, str]]:
        found = [changes for full, changes in self.changes.items() if full.split(".")[-1] == name]
        assert found, f"no signal {name} among {sorted(self.changes)[:40]}"
        return found[0]


def read_vcd(path: Path) -> Waves:
    """Enough of IEEE 1364's VCD to check a waveform: scopes, variables, timestamps and value changes."""
    codes: dict[str, list[str]] = {}
    changes: dict[str, list[tuple[int, str]]] = {}
    scope: list[str] = []
    timescale, now, start = "", -1, -1
    tokens = iter(path.read_text().split())
    for token in tokens:
        if token == "$timescale":
            timescale = "".join(iter(lambda: next(tokens), "$end"))
        elif token == "$scope":
            scope.append([next(tokens), next(tokens)][1])
            next(tokens)
        elif token == "$upscope":
            scope.pop()
            next(tokens)
        elif token == "$var":
            _kind, _width, code, name, *_rest = iter(lambda: next(tokens), "$end")
            codes.setdefault(code, []).append(".".join([*scope, name]))
        elif token.startswith("#"):
            now = int(token[1:])
            start = now if start < 0 else start
        elif token[0] in "01xzXZ" and len(token) > 1:
            for name in codes.get(token[1:], []):
                changes.setdefault(name, []).append((now, token[0]))
        elif token[0] in "bB":
            code = next(tokens)
            for name in codes.get(code, []):
                changes.setdefault(name, []).append((now, token[1:]))
    for name in (n for names in codes.values() for n in names):
        changes.setdefault(name, [])
    return Waves(timescale, changes, start, now)


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
    # the figures say which clock they use: clock_mhz, or the Fmax of a `hw bitstream` run where that is lower
    assert re.search(r"fpga target fpga: \d+ cycles simulated \([\d.]+ ms at [\d.]+ MHz, (clock_mhz|the Fmax place "
                     r"and route achieved).*\) in [\d.]+ s of simulation", result.stderr), result.stderr
    # a 64x48 image is 3072 pixels, 384 beats of 8: the Sobel takes a cycle a beat, its header a few more
    per_message = re.search(r"sobel -> software on /image_edges .*: 8 messages, \d+ beats, (\d+) cycles per message "
                            r"\(([\d.]+) µs at [\d.]+ MHz\)", result.stderr)
    assert per_message is not None, result.stderr
    assert 384 <= int(per_message.group(1)) < 450, result.stderr


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
    result = launch(project, tmp_path, "--trace", "waves")
    assert result.returncode == 0, result.stderr
    assert "fpga target fpga in amaranth" in result.stderr
    assert re.search(r"fpga target fpga: waveform: \S+/waves/fpga.vcd \(cycles 0 to \d+\)", result.stderr), \
        result.stderr
    clock = read_vcd(tmp_path / "waves" / "fpga.vcd").values("clk")
    assert len(clock) > 10, "Amaranth's writer traced the run"
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
    # the hardware's time is the hardware's: cycles a full subscriber held the output back are counted apart,
    # and every port reports the cycles per message of the same run with a subscriber that keeps up
    assert re.search(r"cycles simulated .*; \d+ of them with an output held back by a full software subscriber",
                     result.stderr), result.stderr
    fast = launch(_echo_project(tmp_path), tmp_path)
    assert fast.returncode == 0, fast.stderr
    per_port = [re.findall(r"(gateway of fpga, .*?): 300 messages, \d+ beats, (\d+) cycles per message", run.stderr)
                for run in (result, fast)]
    assert len(per_port[0]) == 2 and per_port[0] == per_port[1], per_port


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


TWO_PORTS = '''
import numpy as np

from hetros import Node
from hetros.hw.reference import sobel
from hetros.interfaces.sensor_msgs.msg import Image
from hetros.interfaces.std_msgs.msg import UInt8MultiArray


def small_source(node: Node) -> None:
    """As fast as the graph takes them: the small messages run far ahead of the images."""
    small = node.create_publisher(UInt8MultiArray, "/a")
    for seq in range(node.get_parameter("pairs")):
        small.publish(UInt8MultiArray(data=bytes([seq]) * 8))


def image_source(node: Node) -> None:
    images = node.create_publisher(Image, "/b")
    for seq in range(node.get_parameter("pairs")):
        pixels = ((np.arange(48 * 64) * (seq + 3)) % 251).astype(np.uint8)
        images.publish(Image(height=48, width=64, encoding="mono8", step=64, data=pixels))


def sink(node: Node) -> None:
    """Takes one of each per pair, /a_out first: a full /a_out waits for /b_out, as a software node would."""
    small, images = node.create_subscription(UInt8MultiArray, "/a_out"), node.create_subscription(Image, "/b_out")
    for seq in range(node.get_parameter("pairs")):
        echoed, edges = small.take(timeout=60), images.take(timeout=60)
        pixels = ((np.arange(48 * 64) * (seq + 3)) % 251).astype(np.uint8).reshape(48, 64)
        if bytes(echoed.data) != bytes([seq]) * 8 or not np.array_equal(edges.data.reshape(48, 64), sobel(pixels)):
            raise ValueError(f"pair {seq} came back wrong")
    node.log.info("%d pairs through two ports of one target", node.get_parameter("pairs"))


def echo(node: Node) -> None:
    out = node.create_publisher(UInt8MultiArray, "/a_out")
    node.create_subscription(UInt8MultiArray, "/a", out.publish)


def edges(node: Node) -> None:
    out = node.create_publisher(Image, "/b_out")

    def filtered(image: Image) -> None:
        pixels = sobel(np.asarray(image.data).reshape(image.height, image.width))
        out.publish(Image(height=image.height, width=image.width, encoding="mono8", step=image.width,
                          data=pixels.reshape(-1)))

    node.create_subscription(Image, "/b", filtered)
'''


@pytest.mark.parametrize("mapping", ["process", "fpga"])
def test_a_full_subscriber_holds_back_only_its_own_port(tmp_path: Path, mapping: str) -> None:
    """Echo on /a -> /a_out and Sobel on /b -> /b_out on one target; the sink takes /a_out, then /b_out, 30
    times. /a_out's subscriber is full long before the first image is through: on a board TREADY goes low
    at that output and the Sobel runs on, so the fpga mapping completes as the process mapping does."""
    (tmp_path / "nodes.py").write_text(TWO_PORTS)
    hardware = "{kind: fpga, data_width: 64}" if mapping == "fpga" else "{kind: process}"
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""\
        name: two_ports
        targets:
          io: {{kind: process}}
          hw: {hardware}
        nodes:
          small:  {{run: nodes:small_source, target: io, parameters: {{pairs: 30}},
                   publish: {{/a: std_msgs/msg/UInt8MultiArray}}}}
          images: {{run: nodes:image_source, target: io, parameters: {{pairs: 30}},
                   publish: {{/b: sensor_msgs/msg/Image}}}}
          echo:   {{run: nodes:echo, hw: "hetros.hw.nodes:Echo", target: hw,
                   parameters: {{source: /a, sink: /a_out}},
                   subscribe: {{/a: std_msgs/msg/UInt8MultiArray}}, publish: {{/a_out: std_msgs/msg/UInt8MultiArray}}}}
          sobel:  {{run: nodes:edges, hw: "hetros.hw.nodes:Sobel", target: hw,
                   parameters: {{source: /b, sink: /b_out, width: 64}},
                   subscribe: {{/b: sensor_msgs/msg/Image}}, publish: {{/b_out: sensor_msgs/msg/Image}}}}
          sink:   {{run: nodes:sink, target: io, required: true, parameters: {{pairs: 30}},
                   subscribe: {{/a_out: std_msgs/msg/UInt8MultiArray, /b_out: sensor_msgs/msg/Image}}}}
        topics:
          /a: {{depth: 2}}
          /a_out: {{depth: 2}}
          /b: {{depth: 2}}
          /b_out: {{depth: 2}}
        """))
    result = launch(tmp_path / "project.yaml", tmp_path)
    assert result.returncode == 0, result.stderr
    assert "30 pairs through two ports of one target" in result.stderr


SLOW_DISPLAY = '''
import time

import numpy as np

from hetros import Node
from hetros.interfaces.sensor_msgs.msg import Image


def camera(node: Node) -> None:
    """As fast as the graph takes them: frames queue in front of the hardware."""
    pub = node.create_publisher(Image, "/image_raw")
    for seq in range(12):
        pixels = ((np.arange(48 * 64) * (seq + 3)) % 251).astype(np.uint8)
        pub.publish(Image(height=48, width=64, encoding="mono8", step=64, data=pixels))


def sobel(node: Node) -> None:
    """The software mapping's filter (unused: the fpga mapping runs the hardware)."""


def display(node: Node) -> None:
    edges = node.create_subscription(Image, "/image_edges")
    for _ in range(12):
        edges.take(timeout=60)
        time.sleep(node.get_parameter("pause"))
    node.log.info("12 frames shown")
'''


def test_hardware_cycles_are_the_same_behind_a_slow_subscriber(tmp_path: Path) -> None:
    """A display that keeps the Sobel's output full holds the filter back mid-frame, its input with it: the
    cycles it waits on software are reported apart, and each port's hardware cycles are those of a run whose
    display keeps up (they were 200,000 cycles a message where 400 were the hardware's). Within 5 %: when the
    frames reach the filter changes how the end of one overlaps the start of the next, by a few cycles."""
    (tmp_path / "nodes.py").write_text(SLOW_DISPLAY)
    project = (EXAMPLES / "sobel_hw" / "project_fpga.yaml").read_text()
    project = project.replace("parameters: {frames: 8, height: 48, width: 64},", "")
    project = project.replace("/image_edges: {depth: 4}", "/image_edges: {depth: 1}")
    runs = {}
    for pause in (0.0, 0.05):
        (tmp_path / "project.yaml").write_text(project.replace(
            "parameters: {frames: 8, height: 48, width: 64, out: out/sobel_hw},", f"parameters: {{pause: {pause}}},"))
        result = launch(tmp_path / "project.yaml", tmp_path)
        assert result.returncode == 0 and "12 frames shown" in result.stderr, result.stderr
        runs[pause] = result.stderr
    waited = re.findall(r"software -> sobel on /image_raw .*: 12 messages, \d+ beats, (\d+) cycles per message .*; "
                        r"besides, (\d+) cycles per message waiting on software", runs[0.05])
    assert waited, runs[0.05]
    per_port = [dict(re.findall(r"(gateway of fpga, .*?): 12 messages, \d+ beats, (\d+) cycles per message", text))
                for text in runs.values()]
    assert len(per_port[0]) == 2 and per_port[0].keys() == per_port[1].keys(), per_port
    for port, cycles in per_port[0].items():
        assert abs(int(per_port[1][port]) - int(cycles)) <= 0.05 * int(cycles), per_port
    hardware, software = map(int, waited[0])
    assert software > hardware, "the display held the filter back for longer than it took to filter a frame"


# three ways a Verilog node breaks AXI4-Stream that a fast subscriber never shows: only a harness that
# stalls its ports, as a verification team's does, catches them (hetros launch --hw-stalls SEED)
_BROKEN = {
    "ignores TREADY": ("""\
    assign a_TREADY = 1'b1;
    always @(posedge ap_clk) begin
        if (!ap_rst_n) b_TVALID <= 1'b0;
        else begin
            b_TVALID <= a_TVALID; b_TDATA <= a_TDATA; b_TKEEP <= a_TKEEP; b_TLAST <= a_TLAST;
        end
    end
""", r"TVALID dropped|TDATA/TKEEP/TLAST changed"),
    "drops TVALID early": ("""\
    assign a_TREADY = !b_TVALID;
    always @(posedge ap_clk) begin
        if (!ap_rst_n) b_TVALID <= 1'b0;
        else if (b_TVALID) b_TVALID <= 1'b0;
        else if (a_TVALID) begin
            b_TVALID <= 1'b1; b_TDATA <= a_TDATA; b_TKEEP <= a_TKEEP; b_TLAST <= a_TLAST;
        end
    end
""", r"TVALID dropped"),
    "changes TDATA while stalled": ("""\
    reg [7:0] tick;
    assign a_TREADY = !b_TVALID || b_TREADY;
    always @(posedge ap_clk) begin
        if (!ap_rst_n) begin b_TVALID <= 1'b0; tick <= 8'd0; end
        else begin
            tick <= tick + 8'd1;
            if (a_TREADY) begin
                b_TVALID <= a_TVALID; b_TDATA <= a_TDATA; b_TKEEP <= a_TKEEP; b_TLAST <= a_TLAST;
            end else b_TDATA <= b_TDATA ^ {56'd0, tick};
        end
    end
""", r"TDATA/TKEEP/TLAST changed"),
}


def test_a_verilog_node_that_ignores_tready_is_caught_at_its_gateway_port(tmp_path: Path) -> None:
    """A slow subscriber behind the gateway takes TREADY low at the node's output: a node that overwrites a
    beat nobody took breaks AXI4-Stream, and the launch names the port and the rule instead of losing data."""
    # an echo that takes a beat every cycle and overwrites its output whether or not it was taken
    project = _verilog_echo(tmp_path, _BROKEN["ignores TREADY"][0], sink=", pause: 0.02")
    result = launch(project, tmp_path)
    assert result.returncode != 0
    assert re.search(r"hardware node echo port 'b' \(/b\): .*before TREADY at cycle \d+", result.stderr), result.stderr


@pytest.mark.parametrize("fault", sorted(_BROKEN))
def test_random_stalls_catch_a_broken_node_behind_a_fast_subscriber(tmp_path: Path, fault: str) -> None:
    body, rule = _BROKEN[fault]
    project = _verilog_echo(tmp_path, body)
    result = launch(project, tmp_path, "--hw-stalls", "7", "--trace", "waves", "--trace-ports")
    assert result.returncode != 0, f"a node that {fault} passed under stalls:\n{result.stderr}"
    found = re.search(rf"hardware node echo port 'b' \(/b\): .*({rule}).* before TREADY at cycle (\d+); waveform: "
                      rf"(\S+) \(cycles \d+ to (\d+)\)", result.stderr)
    assert found, result.stderr
    cycle, path, last = int(found.group(2)), Path(found.group(3)), int(found.group(4))
    assert cycle == last, "the waveform ends at the violation"
    waves = read_vcd(path)
    assert {name.count(".") for name in waves.changes} == {1}, "--trace-ports: the top module's ports only"
    if fault == "changes TDATA while stalled":
        # what GTKWave shows at the violation: the node's output offered, not taken, and its data changing
        at = {name: dict(waves.values(f"m_axis_b_hetros_gateway_fpga_{name}")) for name in ("tvalid", "tready")}
        data = waves.values("m_axis_b_hetros_gateway_fpga_tdata")
        before = [value for time, value in data if time <= (cycle - 1) * 10_000][-1]
        after = [value for time, value in data if time <= cycle * 10_000][-1]
        assert before != after, "TDATA changed at the cycle named"
        state = {name: [v for t, v in sorted(changes.items()) if t <= (cycle - 1) * 10_000 + 5_000][-1]
                 for name, changes in at.items()}
        assert state == {"tvalid": "1", "tready": "0"}, "offered and stalled the cycle before"


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_well_behaved_verilog_node_passes_under_random_stalls(tmp_path: Path, seed: int) -> None:
    """examples/ping_pong's HLS-shaped echo, unchanged, under three stall seeds: every message in order and
    intact (the stalls change when beats move, never what arrives)."""
    text = (EXAMPLES / "ping_pong" / "rtl" / "echo_hls.v").read_text().replace("send_", "a_").replace("recv_", "b_")
    project = _verilog_echo(tmp_path, text[text.index("    assign a_TREADY"):text.index("endmodule")])
    result = launch(project, tmp_path, "--hw-stalls", f"{seed}:40")
    assert result.returncode == 0, result.stderr
    assert "300 messages through the hardware, in order and intact" in result.stderr


def _verilog_echo(tmp_path: Path, body: str, sink: str = "") -> Path:
    """examples/ping_pong's HLS-shaped echo with its body replaced, on /a -> /b of the echo project."""
    (tmp_path / "rtl").mkdir(exist_ok=True)
    text = (EXAMPLES / "ping_pong" / "rtl" / "echo_hls.v").read_text().replace("send_", "a_").replace("recv_", "b_")
    head = text[:text.index("    assign a_TREADY")]
    (tmp_path / "rtl" / "echo.v").write_text(head + body + "endmodule\n")
    project = _echo_project(tmp_path, sink=sink)
    text = project.read_text().replace('hw: "hetros.hw.nodes:Echo"', "hw: rtl/echo.v:echo_hls")
    text = text.replace("parameters: {source: /a, sink: /b},", "")
    project.write_text(text.replace("data_width: 32", "data_width: 64"))
    return project


def test_a_hardware_message_longer_than_its_type_is_refused_at_the_gateway(tmp_path: Path) -> None:
    """A node that ends its messages with a whole beat (TKEEP all ones) sends bytes beyond the message: the
    gateway names the port and the sizes instead of publishing something else than the node meant."""
    project = _verilog_echo(tmp_path, """\
    assign a_TREADY = !b_TVALID || b_TREADY;
    always @(posedge ap_clk) begin
        if (!ap_rst_n) b_TVALID <= 1'b0;
        else if (a_TREADY) begin
            b_TVALID <= a_TVALID; b_TDATA <= a_TDATA; b_TLAST <= a_TLAST;
            b_TKEEP <= a_TLAST ? 8'hFF : a_TKEEP;
        end
    end
""")
    result = launch(project, tmp_path)
    assert result.returncode != 0
    assert re.search(r"echo -> software on /b .*: the hardware sent \d+ bytes, but a std_msgs/msg/UInt8MultiArray "
                     r"with the fields it holds is \d+ bytes", result.stderr), result.stderr


def test_a_node_that_never_takes_its_input_stops_the_launch_at_its_bound(tmp_path: Path) -> None:
    project = _verilog_echo(tmp_path, """\
    assign a_TREADY = 1'b0;
    always @(posedge ap_clk) b_TVALID <= 1'b0;
""")
    project.write_text(project.read_text().replace("data_width: 64", "data_width: 64, stuck_cycles: 200000"))
    result = launch(project, tmp_path, "--trace", "waves", "--trace-window", "30000")
    assert result.returncode == 1, result.stderr
    found = re.search(r"software -> echo on /a \(port (\w+)\): hardware node echo has taken no beat for (\d+) cycles "
                      r"while a message waits \(TREADY low at its input, cycle (\d+)\): check its TREADY logic, or "
                      r"raise targets.fpga.stuck_cycles \(200000\) for a node that may rightly wait that long; "
                      r"waveform: (\S+) \(cycles (\d+) to (\d+)\)", result.stderr)
    assert found, result.stderr
    prefix, waited, stopped, path, first, last = found.groups()
    assert 200_000 < int(waited) < 10_000_000, "the project's bound, not the default"
    assert "PublishTimeoutError" not in result.stderr, "the hardware's cause, not a publisher's timeout"
    # the waveform holds the window's last cycles up to the stop, the input offered and never taken
    assert Path(path) == tmp_path / "waves" / "fpga.vcd" and int(last) == int(stopped)
    assert 30_000 <= int(last) - int(first) <= 60_000
    waves = read_vcd(Path(path))
    assert waves.timescale == "1ps"
    valid, ready = (waves.values(f"{prefix}_{s}") for s in ("tvalid", "tready"))
    clock = waves.values("clk")
    assert {value for _, value in ready} == {"0"}, "TREADY never rose"
    assert valid[-1][1] == "1", "a message waits at the input"
    assert waves.end // 10_000 == int(last) and waves.start // 10_000 == int(first), "10 ns a cycle at 100 MHz"
    assert len(clock) > 2 * 30_000, "the clock toggles every half period"
    assert not list((tmp_path / "waves").glob("*.part*")), "the two parts were stitched into one file"


SIZES = '''
import numpy as np

from hetros import Node
from hetros.interfaces.sensor_msgs.msg import Image


def camera(node: Node) -> None:
    """Four images the Sobel's line buffers cannot take (too wide, a header that lies, pixels of the wrong
    size, lines that are not whole 8-byte beats), then one it can."""
    pub = node.create_publisher(Image, "/image_raw")
    for bad in (Image(height=8, width=80, encoding="mono8", step=80, data=np.zeros(640, np.uint8)),
                Image(height=9, width=64, encoding="mono8", step=64, data=np.zeros(512, np.uint8)),
                Image(height=8, width=64, encoding="rgb8", step=64, data=np.zeros(512, np.uint8)),
                Image(height=8, width=60, encoding="mono8", step=60, data=np.zeros(480, np.uint8))):
        pub.publish(bad)
        node.sleep(0.1)  # paced: on a best-effort topic a burst could lose some before the gateway takes them
    for _ in node.rate(10.0):  # until the display has one (best effort may lose one, as it may any)
        pub.publish(Image(height=8, width=64, encoding="mono8", step=64, data=np.full(512, 7, np.uint8)))


def sobel(node: Node) -> None:
    """The software mapping's filter (unused here: the fpga mapping runs the hardware)."""
    out = node.create_publisher(Image, "/image_edges")
    node.create_subscription(Image, "/image_raw", out.publish)


def display(node: Node) -> None:
    edges = node.create_subscription(Image, "/image_edges").take(timeout=60)
    node.log.info("one image through, %dx%d", edges.width, edges.height)
'''


def test_images_a_filter_cannot_take_are_refused_naming_node_port_and_fix(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(SIZES)
    project = (EXAMPLES / "sobel_hw" / "project_fpga.yaml").read_text()
    project = project.replace("parameters: {frames: 8, height: 48, width: 64},", "")
    project = project.replace("parameters: {frames: 8, height: 48, width: 64, out: out/sobel_hw},", "")
    # a reliable topic may lose nothing: the first image the node cannot take stops the launch, with the cause
    (tmp_path / "project.yaml").write_text(project)
    result = launch(tmp_path / "project.yaml", tmp_path)
    assert result.returncode == 1, result.stderr
    assert "hardware node sobel on reliable topic /image_raw refused a message, which a reliable topic may not " \
           "lose: an image line of 80 bytes (80 pixels) is wider than the node's line buffers" in result.stderr
    assert "one image through" not in result.stderr
    # best effort: each refused image is named and dropped, and the graph goes on
    project = project.replace("/image_raw:   {depth: 4}", "/image_raw:   {depth: 4, reliability: best_effort}")
    (tmp_path / "project.yaml").write_text(project.replace("/image_edges: {depth: 4}",
                                                           "/image_edges: {depth: 4, reliability: best_effort}"))
    result = launch(tmp_path / "project.yaml", tmp_path)
    assert result.returncode == 0, result.stderr
    assert "one image through, 64x8" in result.stderr
    refused = re.findall(r"hardware node sobel on /image_raw refused a message \(\d so far; it never went in\): (.*)",
                         result.stderr)
    reasons = ["wider than the node's line buffers (64 pixels of 1 bytes): set the node's width parameter to at "
               "least 80", "header says 9 rows of 64 bytes (576 bytes) carries 512 bytes",
               "a rgb8 image has 3-byte pixels, but this node takes 1-byte pixels",
               "an image line of 60 bytes is not a whole number of 8-byte beats, which this full-width node takes a "
               "cycle each: send images whose step is a multiple of 8, or set the node's lanes parameter to 1"]
    named = [next(i for i, reason in enumerate(reasons) if reason in line) for line in refused]
    assert len(named) >= 3 and named == sorted(set(named)), result.stderr  # in order; best effort may lose one
