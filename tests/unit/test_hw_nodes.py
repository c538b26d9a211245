"""Hardware nodes: a node's Amaranth implementation, bit-exact against its software node, its ports
checked against its topics, and wired into the fpga target's top module."""

from __future__ import annotations

import json
import textwrap
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("amaranth")

from amaranth import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from hetros.hw import BeatCodec
from hetros.hw.nodes import Echo, NodeUnderTest, port_problems
from hetros.hw.sim._sim import simulate
from hetros.hw.streams._axi import axi_stream
from hetros.msg import registry
from hetros.project import check, load_project, plan
from hetros.runtime import Graph, Node

pytestmark = pytest.mark.rtl
TYPE = "sensor_msgs/msg/Image"


def software_echo(node: Node) -> None:
    """The software node the hardware Echo stands in for: every message republished as it came."""
    cls = registry().get(TYPE)
    pub = node.create_publisher(cls, "/recv")
    for message in node.create_subscription(cls, "/send"):
        pub.publish(message)


def _run_software(inputs: list[Any]) -> list[Any]:
    """What ``software_echo`` publishes for ``inputs``, run as a node of a graph."""
    graph = Graph.standalone()
    cls = registry().get(TYPE)
    received = Node("test", graph).create_subscription(cls, "/recv")
    echo = threading.Thread(target=software_echo, args=(Node("echo", graph),), daemon=True)
    echo.start()
    sender = Node("source", graph).create_publisher(cls, "/send")
    try:
        outputs = []
        for message in inputs:
            sender.publish(message)
            outputs.append(received.take(timeout=10))
        return outputs
    finally:
        graph.shutdown()
        echo.join(5)


def test_the_echo_hardware_node_is_bit_exact_against_its_software_node() -> None:
    rng = np.random.default_rng(7)
    cls = registry().get(TYPE)
    inputs = []
    for size in (0, 1, 7, 8, 9, 63, 64, 65, 300, 1500):
        height = int(rng.integers(1, 9))
        inputs.append(cls(height=height, width=size, encoding=rng.choice(["mono8", "rgb8", ""]),
                          step=size, data=rng.integers(0, 256, size * height, dtype=np.uint8)))
    expected = [BeatCodec(registry(), TYPE, 64).body(m) for m in _run_software(inputs)]
    for width in (32, 64, 128):
        codec = BeatCodec(registry(), TYPE, width)
        node = NodeUnderTest(Echo("/send", "/recv", width), ["send"], ["recv"], width)
        result = simulate(node, [[codec.body(m) for m in inputs]], idle=0.3, stall=0.3, seed=width)
        assert result.received[0] == expected, f"data_width {width}"


def test_port_problems_name_each_missing_extra_and_mis_shaped_port() -> None:
    echo = Echo("/send", "/recv", 64)
    echo._MustUse__silence = True  # only its ports are looked at
    assert port_problems(echo, ["/recv"], ["/send"], 64) == []
    assert port_problems(echo, ["/recv"], ["/send"], 32) == [
        "port 'recv' must be Out(axi_stream(32)) for /recv, not " + repr(echo.signature.members["recv"]),
        "port 'send' must be In(axi_stream(32)) for /send, not " + repr(echo.signature.members["send"])]
    assert port_problems(echo, ["/recv", "/extra"], [], 64) == [
        "port 'extra' is missing: the node publishes /extra, so its component needs Out(axi_stream(64)) named 'extra'",
        "port 'send' is not one of the node's topics (extra, recv); declare the topic or remove the port"]


_PROJECT = """
name: hwnode
targets: {{fpga0: {{kind: fpga, data_width: 64}}}}
nodes:
  source: {{run: nodes:idle, target: fpga0, publish: {{/send: {type}}}}}
  echo:   {{run: nodes:idle, hw: "hwnodes:{component}", target: fpga0,
           subscribe: {{/send: {type}}}, publish: {{/recv: {type}}}}}
  sink:   {{run: nodes:idle, target: fpga0, subscribe: {{/recv: {type}}}}}
"""
_NODES = """
from hetros.hw.nodes import Echo

def idle(node):
    pass

def good(data_width):
    return Echo("/send", "/recv", data_width)

def wrong(data_width):
    return Echo("/send", "/back", data_width)
"""


def _project(tmp_path: Path, component: str) -> Path:
    (tmp_path / "nodes.py").write_text("def idle(node):\n    pass\n", encoding="utf-8")
    (tmp_path / "hwnodes.py").write_text(textwrap.dedent(_NODES), encoding="utf-8")
    path = tmp_path / "project.yaml"
    path.write_text(textwrap.dedent(_PROJECT.format(type=TYPE, component=component)), encoding="utf-8")
    return path


def test_check_names_the_port_a_hardware_node_lacks(tmp_path: Path) -> None:
    report = check(load_project(_project(tmp_path, "wrong")))
    assert any("nodes.echo.hw: port 'recv' is missing: the node publishes /recv" in e for e in report.errors), \
        report.errors
    assert any("port 'back' is not one of the node's topics" in e for e in report.errors)
    assert not check(load_project(_project(tmp_path, "good"))).errors


def test_hw_build_wires_a_hardware_node_inside_the_top(tmp_path: Path) -> None:
    from hetros.hw import build_target

    built = plan(load_project(_project(tmp_path, "good")))
    verilog, manifest_path = build_target(built, "fpga0", tmp_path / "out", registry())
    manifest = json.loads(manifest_path.read_text())
    assert manifest["hardware_nodes"] == {"echo": "hwnodes:good"}
    names = {port["name"] for port in manifest["ports"]}
    assert "s_axis_send_source_tdata" in names and "m_axis_recv_sink_tdata" in names
    assert not any("_echo_" in name for name in names), "the hardware node's endpoints are inside the top"
    # the echo sits between the two networks: the source's beats reach the sink's port through it
    assert "assign m_axis_recv_sink_tvalid = s_axis_send_source_tvalid;" in verilog.read_text()


class _Flaky(wiring.Component):
    """A broken hardware node: it shows each beat for one cycle only, taken or not."""

    def __init__(self, data_width: int = 64) -> None:
        super().__init__({"send": In(axi_stream(data_width)), "recv": Out(axi_stream(data_width))})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        shown = Signal()
        m.d.comb += [self.recv.tdata.eq(self.send.tdata), self.recv.tkeep.eq(self.send.tkeep),
                     self.recv.tlast.eq(self.send.tlast), self.recv.tvalid.eq(self.send.tvalid & ~shown),
                     self.send.tready.eq(self.recv.tready | shown)]
        m.d.sync += shown.eq(self.send.tvalid & ~shown & ~self.recv.tready)
        return m


def test_a_hardware_node_that_breaks_the_stream_rules_is_named_with_its_port_and_cycle() -> None:
    from hetros import HardwareError

    node = NodeUnderTest(_Flaky(64), ["send"], ["recv"], 64, name="flaky")
    with pytest.raises(HardwareError, match=r"hardware node flaky port 'recv''s stream: TVALID dropped at cycle \d+"):
        simulate(node, [[bytes([0]) + bytes(200)]], stall=0.5, seed=3)


def test_a_full_width_compensation_lane_is_one_memory_of_count_and_stretch_entry() -> None:
    """Each lane's histogram word holds its count (24 bits) and its stretch table's entry (8): one block RAM a
    lane, not two (at 512 bits the two made a design nextpnr did not route)."""
    from amaranth.hdl import Fragment

    from hetros.hw.designs._image import Compensation

    memories: dict[str, Any] = {}

    def walk(fragment: Any) -> None:
        for sub, name, *_ in fragment.subfragments:
            if type(sub).__name__ == "MemoryInstance":
                memories[name] = sub._data
            walk(sub)

    walk(Fragment.get(Compensation("image_in", "image_out", data_width=64, width=640, channels=3), None))
    lanes = {name: data for name, data in memories.items() if name.startswith("histogram")}
    assert sorted(lanes) == [f"histogram{k}" for k in range(8)]
    assert {(data.shape.width, data.depth) for data in lanes.values()} == {(32, 256)}
    assert not [name for name in memories if name.startswith("stretch")]
    assert [int(word) >> 24 for word in lanes["histogram0"].init] == list(range(256))  # the first frame as it is


def test_the_median_s_three_way_choice_gives_low_middle_and_high_of_every_triple() -> None:
    """The full-width median chooses each of the three by the same three comparisons side by side; every
    triple of 3-bit values, ties included, against Python's sort."""
    from amaranth.sim import Simulator

    from hetros.hw.designs._lanes import low_middle_high

    m = Module()
    inputs = [Signal(3, name=name) for name in "abc"]
    outputs = [Signal(3, name=name) for name in ("low", "middle", "high")]
    m.d.comb += [output.eq(value) for output, value in zip(outputs, low_middle_high(*inputs), strict=True)]
    seen: list[tuple[tuple[int, ...], tuple[int, ...]]] = []

    async def bench(ctx: Any) -> None:
        for number in range(8 ** 3):
            triple = (number >> 6, (number >> 3) & 7, number & 7)
            for signal, value in zip(inputs, triple, strict=True):
                ctx.set(signal, value)
            seen.append((triple, tuple(ctx.get(output) for output in outputs)))

    sim = Simulator(m)
    sim.add_testbench(bench)
    sim.run()
    assert len(seen) == 512
    assert all(chosen == tuple(sorted(triple)) for triple, chosen in seen)
