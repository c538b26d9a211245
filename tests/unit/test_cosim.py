"""Co-simulation: an fpga target's hardware in Verilator behind its gateway, driven as ``hetros launch``
drives it. The image filters are held bit for bit to their numpy twins on random images; a hardware
node that breaks the AXI4-Stream rules is named with its port and the cycle."""

from __future__ import annotations

import shutil
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("amaranth")

from hetros import HardwareError
from hetros.hw.reference import gaussian_blur, sobel
from hetros.hw.sim._cosim import TargetSimulation
from hetros.msg import registry
from hetros.plan import Plan, gateway_node
from hetros.project import load_project, plan

pytestmark = [pytest.mark.rtl,
              pytest.mark.skipif(shutil.which("verilator") is None, reason="Debian's verilator is not installed")]
IMAGE = "sensor_msgs/msg/Image"


def _filter_project(tmp_path: Path, component: str, data_width: int, width: int = 0, typename: str = IMAGE,
                    parameter: str = "", sim: str = "verilator") -> Plan:
    parameter = parameter or f"width: {width}"
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""\
        name: filter
        targets:
          io: {{kind: process}}
          fpga: {{kind: fpga, data_width: {data_width}, sim: {sim}}}
        nodes:
          camera: {{run: json:dumps, target: io, publish: {{/raw: {typename}}}}}
          filter: {{run: json:dumps, hw: "{component}", target: fpga,
                   parameters: {{source: /raw, sink: /out, {parameter}}},
                   subscribe: {{/raw: {typename}}}, publish: {{/out: {typename}}}}}
          display: {{run: json:dumps, target: io, subscribe: {{/out: {typename}}}}}
        """))
    return plan(load_project(tmp_path / "project.yaml"))


def _through(simulation: TargetSimulation, messages: list[Any], typename: str = IMAGE) -> list[Any]:
    """Each message pushed into the gateway's input, what the hardware published for it."""
    codec = registry().codec(typename)
    top = simulation.top
    out = []
    for message in messages:
        body = bytearray(codec.size(message))
        codec.encode(message, memoryview(body))
        top.push(0, bytes(body))
        got = None
        for _ in range(1000):
            top.run(1_000_000, 10_000)
            got = top.pop(0)
            if got is not None:
                break
        assert got is not None, "the hardware published nothing for a message"
        out.append(codec.decode(memoryview(got)))
    return out


def _through_target(planned: Plan, messages: list[Any]) -> list[Any]:
    """:func:`_through` on a fresh simulation of the plan's fpga target, closed after."""
    simulation = TargetSimulation(planned, "fpga", registry())
    try:
        return _through(simulation, messages)
    finally:
        simulation.close()


@pytest.mark.parametrize(("component", "twin", "data_width", "lanes"), [
    ("hetros.hw.nodes:Sobel", sobel, 64, 1),
    ("hetros.hw.nodes:Sobel", sobel, 8, 1),
    ("hetros.hw.nodes:Sobel", sobel, 128, 1),
    ("hetros.hw.nodes:GaussianBlur", gaussian_blur, 64, 1),
    ("hetros.hw.nodes:Sobel", sobel, 32, 4),
    ("hetros.hw.nodes:Sobel", sobel, 64, 8),
    ("hetros.hw.nodes:Sobel", sobel, 128, 16),
    ("hetros.hw.nodes:GaussianBlur", gaussian_blur, 64, 8),
])
def test_image_filters_are_bit_exact_against_their_software_twins(tmp_path: Path, component: str, twin: Any,
                                                                   data_width: int, lanes: int) -> None:
    """A byte a cycle, every image shape; a beat a cycle (``lanes`` bytes), every shape whose lines are whole
    beats (the node refuses the others in software, see test_hw.py)."""
    planned = _filter_project(tmp_path, component, data_width, parameter=f"width: 48, lanes: {lanes}")
    simulation = TargetSimulation(planned, "fpga", registry())
    rng = np.random.default_rng(data_width + lanes)
    cls = registry().get(IMAGE)
    # every shape class: the elaborated width and narrower, one and two lines, too small for a window
    shapes = [(30, 48), (17, 23), (3, 3), (1, 9), (2, 5), (9, 1), (5, 40), (3, 16), (4, 32), *((
              int(rng.integers(3, 30)), int(rng.integers(3, 49))) for _ in range(6)),
              *((int(rng.integers(1, 30)), lanes * int(rng.integers(1, 48 // lanes + 1))) for _ in range(6))]
    shapes = [shape for shape in shapes if shape[1] % lanes == 0]
    images = [rng.integers(0, 256, shape, dtype=np.uint8) for shape in shapes]
    messages = []
    for index, image in enumerate(images):
        message = cls(height=image.shape[0], width=image.shape[1], encoding="mono8", step=image.shape[1],
                      data=image.reshape(-1))
        message.header.frame_id = "f" * (index % 7)  # every alignment of the fields after it
        message.header.stamp.sec = index
        messages.append(message)
    try:
        outputs = _through(simulation, messages)
    finally:
        simulation.close()
    for image, message, output in zip(images, messages, outputs, strict=True):
        assert (output.header.frame_id, output.header.stamp.sec) == (message.header.frame_id, message.header.stamp.sec)
        assert (output.height, output.width, output.encoding, output.step) == (*image.shape, "mono8", image.shape[1])
        np.testing.assert_array_equal(np.asarray(output.data).reshape(image.shape), twin(image))


def test_a_full_frame_of_sobel_takes_a_cycle_a_beat(tmp_path: Path) -> None:
    """The line buffers keep up with the stream: 640x480 mono8 at 64 bits in about 38,400 cycles."""
    planned = _filter_project(tmp_path, "hetros.hw.nodes:Sobel", 64, width=640)
    simulation = TargetSimulation(planned, "fpga", registry())
    image = np.random.default_rng(1).integers(0, 256, (480, 640), dtype=np.uint8)
    message = registry().get(IMAGE)(height=480, width=640, encoding="mono8", step=640, data=image.reshape(-1))
    try:
        before = simulation.top.cycle
        (output,) = _through(simulation, [message])
        cycles = simulation.top.cycle - before
    finally:
        simulation.close()
    np.testing.assert_array_equal(np.asarray(output.data).reshape(480, 640), sobel(image))
    # a beat of 8 pixels a cycle; the run's idle tail is at most 10,000 cycles
    assert 640 * 480 // 8 <= cycles < 640 * 480 // 8 * 1.02 + 20_000


def test_a_frame_without_pixels_leaves_as_it_came_and_the_next_is_filtered() -> None:
    """Hardware publishers are not checked in software: empty images (a message that ends in its header)
    between real ones, under back-pressure, at the full width."""
    from hetros.hw.nodes import NodeUnderTest, Sobel
    from hetros.hw.sim._sim import simulate

    codec, cls = registry().codec(IMAGE), registry().get(IMAGE)
    rng = np.random.default_rng(1)
    images = [rng.integers(0, 256, shape, dtype=np.uint8) for shape in [(0, 0), (4, 16), (0, 0), (0, 0), (5, 8)]]
    bodies = []
    for index, image in enumerate(images):
        message = cls(height=image.shape[0], width=image.shape[1], encoding="mono8", step=image.shape[1],
                      data=image.reshape(-1))
        message.header.frame_id = "ab" * index
        body = bytearray(codec.size(message))
        codec.encode(message, memoryview(body))
        bodies.append(bytes(body))
    result = simulate(NodeUnderTest(Sobel("/a", "/b", 64, width=32), ["a"], ["b"], 64), [bodies], stall=0.3,
                      idle=0.2, seed=2)
    assert [codec.decode(memoryview(body)).header.frame_id for body in result.received[0]] == [
        "ab" * index for index in range(len(images))]
    for image, body in zip(images, result.received[0], strict=True):
        pixels = np.asarray(codec.decode(memoryview(body)).data)
        np.testing.assert_array_equal(pixels, sobel(image).reshape(-1) if image.size else pixels[:0])


def test_the_gateway_ports_are_named_after_topic_and_target(tmp_path: Path) -> None:
    planned = _filter_project(tmp_path, "hetros.hw.nodes:Sobel", 64, width=40)
    gateway = gateway_node("fpga")
    assert planned.process_of(gateway) == "fpga" and planned.nodes_in("fpga") == [gateway]
    assert {(e.channel, e.publisher, e.subscriber, e.transport) for e in planned.edges} == {
        ("/raw", "camera", gateway, "shm"), ("/out", gateway, "display", "shm")}
    simulation = TargetSimulation(planned, "fpga", registry())
    try:
        assert [p.port.prefix for p in simulation.inputs] == [f"s_axis_raw_{gateway}"]
        assert [p.port.prefix for p in simulation.outputs] == [f"m_axis_out_{gateway}"]
        assert "software -> filter on /raw" in simulation.inputs[0].port.label
    finally:
        simulation.close()


def _guide_threshold() -> str:
    """The threshold filter of the FPGA guide (docs/GUIDE.md), as the guide prints it."""
    guide = (Path(__file__).resolve().parents[2] / "docs" / "GUIDE.md").read_text()
    code = guide.split("A filter of your own on `sensor_msgs/Image`", 1)[1].split("```python\n", 1)[1]
    return code.split("```", 1)[0]


def test_the_guides_threshold_is_a_full_width_filter_in_a_few_lines(tmp_path: Path) -> None:
    """A newcomer's node from the guide: under 40 lines, mapped, bit exact at a beat a cycle."""
    source = _guide_threshold()
    assert len(source.strip().splitlines()) < 40
    (tmp_path / "threshold.py").write_text(source)
    planned = _filter_project(tmp_path, "threshold:Threshold", 64, parameter="width: 64, level: 100")
    rng = np.random.default_rng(3)
    cls = registry().get(IMAGE)
    images = [rng.integers(0, 256, shape, dtype=np.uint8) for shape in ((6, 16), (20, 64), (3, 8))]
    messages = [cls(height=i.shape[0], width=i.shape[1], encoding="mono8", step=i.shape[1], data=i.reshape(-1))
                for i in images]
    outputs = _through_target(planned, messages)
    for image, output in zip(images, outputs, strict=True):
        expected = np.where(image >= 100, 255, 0).astype(np.uint8)
        expected[0, :] = expected[-1, :] = expected[:, 0] = expected[:, -1] = 0
        np.testing.assert_array_equal(np.asarray(output.data).reshape(image.shape), expected)


FLAKY = """
from amaranth import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out
from hetros.hw.nodes import axi_stream


class Flaky(wiring.Component):
    \"\"\"A broken hardware node: it shows each beat for one cycle only, taken or not.\"\"\"

    def __init__(self, data_width=64, **_):
        super().__init__({"raw": In(axi_stream(data_width)), "out": Out(axi_stream(data_width))})

    def elaborate(self, platform):
        m = Module()
        shown = Signal()
        m.d.comb += [self.out.tdata.eq(self.raw.tdata), self.out.tkeep.eq(self.raw.tkeep),
                     self.out.tlast.eq(self.raw.tlast), self.out.tvalid.eq(self.raw.tvalid & ~shown),
                     self.raw.tready.eq(self.out.tready | shown)]
        m.d.sync += shown.eq(self.raw.tvalid & ~shown & ~self.out.tready)
        return m
"""


def _run_until_raised(top: Any, match: str) -> None:
    with pytest.raises(HardwareError, match=match):
        for _ in range(100):
            top.run(10_000, 1_000)


def test_a_hardware_node_that_breaks_the_stream_rules_is_named_with_its_port_and_cycle(tmp_path: Path) -> None:
    (tmp_path / "flaky.py").write_text(FLAKY)
    planned = _filter_project(tmp_path, "flaky:Flaky", 64, width=40)
    simulation = TargetSimulation(planned, "fpga", registry())
    top = simulation.top
    top.set_output_limit(0, 0)  # the software side takes nothing: the node must hold its beat
    top.push(0, bytes(100))
    try:
        _run_until_raised(top, r"hardware node filter port 'out' \(/out\): TVALID dropped, or TDATA/TKEEP/TLAST "
                               r"changed, before TREADY at cycle \d+")
    finally:
        simulation.close()


NO_LAST = FLAKY.replace("class Flaky", "class NoLast").replace(
    "self.out.tlast.eq(self.raw.tlast)", "self.out.tlast.eq(0)").replace(
    "self.out.tvalid.eq(self.raw.tvalid & ~shown)", "self.out.tvalid.eq(self.raw.tvalid)").replace(
    "self.raw.tready.eq(self.out.tready | shown)", "self.raw.tready.eq(self.out.tready)")


def test_a_hardware_node_that_never_sends_tlast_leaves_its_bytes_counted_not_published(tmp_path: Path) -> None:
    """The gateway cuts messages at TLAST only: bytes without it are held and reported at the end."""
    (tmp_path / "nolast.py").write_text(NO_LAST)
    planned = _filter_project(tmp_path, "nolast:NoLast", 64, width=40)
    simulation = TargetSimulation(planned, "fpga", registry())
    top = simulation.top
    try:
        top.push(0, bytes(range(96)))  # whole beats: held, counted
        for _ in range(10):
            top.run(10_000, 1_000)
        assert top.pop(0) is None and top.partial(0) == 96
        top.push(0, bytes(range(100)))  # ends in a partial beat, which only a last beat may be
        _run_until_raised(top, r"filter -> software on /out .*: a partial beat without TLAST at cycle \d+")
    finally:
        simulation.close()


def test_a_node_on_an_fpga_target_without_hardware_is_named(tmp_path: Path) -> None:
    from hetros import LaunchError
    from hetros.launch import launch

    path = tmp_path / "project.yaml"
    _filter_project(tmp_path, "hetros.hw.nodes:Sobel", 64, width=40)
    path.write_text(path.read_text().replace('hw: "hetros.hw.nodes:Sobel", ', ""))
    planned = plan(load_project(path))
    with pytest.raises(LaunchError, match=r"node\(s\) filter sit on fpga targets without a hardware implementation"):
        launch(planned)


def test_amaranths_simulator_agrees_with_verilator_on_the_sobel_node() -> None:
    """The slow reference simulator, cycle for cycle in Python, gives the same pixels (and the twin's)."""
    from hetros.hw.nodes import NodeUnderTest, Sobel
    from hetros.hw.sim._sim import simulate

    codec = registry().codec(IMAGE)
    image = np.random.default_rng(7).integers(0, 256, (6, 12), dtype=np.uint8)
    message = registry().get(IMAGE)(height=6, width=12, encoding="mono8", step=12, data=image.reshape(-1))
    body = bytearray(codec.size(message))
    codec.encode(message, memoryview(body))
    node = NodeUnderTest(Sobel("/image_raw", "/image_edges", 32, width=12), ["image_raw"], ["image_edges"], 32)
    result = simulate(node, [[bytes(body)]], stall=0.3, idle=0.3, seed=2)
    output = codec.decode(memoryview(result.received[0][0]))
    np.testing.assert_array_equal(np.asarray(output.data).reshape(image.shape), sobel(image))


@pytest.mark.parametrize("data_width", [8, 64, 128])
def test_the_hardware_adder_serves_add_two_ints_bit_exact_in_order(tmp_path: Path, data_width: int) -> None:
    """A service in hardware: request bodies in, response bodies out, one each, in order."""
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""\
        name: adder
        targets:
          io: {{kind: process}}
          fpga: {{kind: fpga, data_width: {data_width}}}
        nodes:
          server: {{run: json:dumps, hw: "hetros.hw.nodes:AddTwoInts", target: fpga,
                   parameters: {{service: /add}}, services: {{/add: example_interfaces/srv/AddTwoInts}}}}
          client: {{run: json:dumps, target: io, clients: {{/add: example_interfaces/srv/AddTwoInts}}}}
        """))
    planned = plan(load_project(tmp_path / "project.yaml"))
    gateway = gateway_node("fpga")
    assert planned.nodes[gateway].services == {"/add": "example_interfaces/srv/AddTwoInts"}
    types = registry()
    request_codec = types.codec("example_interfaces/srv/AddTwoInts_Request")
    response_codec = types.codec("example_interfaces/srv/AddTwoInts_Response")
    request_cls = types.get("example_interfaces/srv/AddTwoInts_Request")
    simulation = TargetSimulation(planned, "fpga", types)
    assert simulation.inputs[0].service == "/add" and simulation.outputs[0].service == "/add"
    rng = np.random.default_rng(data_width)
    pairs = [(int(a), int(b)) for a, b in rng.integers(-2**62, 2**62, (40, 2))] + [(2**63 - 1, 1), (-1, -1)]
    top = simulation.top
    try:
        for a, b in pairs:
            body = bytearray(request_codec.size(request_cls(a=a, b=b)))
            request_codec.encode(request_cls(a=a, b=b), memoryview(body))
            top.push(0, bytes(body))
        sums = []
        for _ in range(100):
            top.run(100_000, 1_000)
            while (produced := top.pop(0)) is not None:
                sums.append(response_codec.decode(memoryview(produced)).sum)
            if len(sums) == len(pairs):
                break
    finally:
        simulation.close()
    wrapped = [(a + b + 2**63) % 2**64 - 2**63 for a, b in pairs]
    assert sums == wrapped


def _unsorted_arrays(seed: int, sizes: list[int]) -> tuple[list[Any], list[np.ndarray[Any, Any]]]:
    """UInt32MultiArray messages of the given lengths (ties, labelled dimensions of every length) and
    what the software sorter answers with each: their numbers sorted."""
    types = registry()
    cls, layout, dim = (types.get(f"std_msgs/msg/{n}") for n in ("UInt32MultiArray", "MultiArrayLayout",
                                                                  "MultiArrayDimension"))
    rng = np.random.default_rng(seed)
    messages, expected = [], []
    for size in sizes:
        values = rng.integers(0, 2**32, int(size), dtype=np.uint32)
        if size % 3 == 1:
            values[: size // 2] = values[0]  # ties
        dims = [dim(label="x" * int(rng.integers(0, 6)), size=int(size), stride=1) for _ in range(int(size) % 3)]
        messages.append(cls(layout=layout(dim=dims, data_offset=int(size)), data=values))
        expected.append(np.sort(values))
    return messages, expected


def _assert_sorted_answers(outputs: list[Any], expected: list[np.ndarray[Any, Any]]) -> None:
    assert len(outputs) == len(expected)
    for output, want in zip(outputs, expected, strict=True):
        assert list(output.layout.dim) == [] and output.layout.data_offset == 0
        np.testing.assert_array_equal(np.asarray(output.data), want)


@pytest.mark.parametrize("data_width", [8, 64, 128])
def test_the_hardware_sorter_publishes_what_the_software_sorter_does(tmp_path: Path, data_width: int) -> None:
    """Random arrays of every awkward length, layouts with labelled dimensions (skipped, every alignment),
    against the software node's answer: ``UInt32MultiArray(data=np.sort(data))``."""
    array = "std_msgs/msg/UInt32MultiArray"
    planned = _filter_project(tmp_path, "hetros.hw.nodes:Sorter", data_width, typename=array,
                              parameter="capacity: 64")
    sizes = [0, 1, 2, 3, 17, 63, 64, 33, 64, 5, *np.random.default_rng(data_width).integers(0, 65, 6)]
    messages, expected = _unsorted_arrays(data_width, sizes)
    simulation = TargetSimulation(planned, "fpga", registry())
    try:
        outputs = _through(simulation, messages, array)
    finally:
        simulation.close()
    _assert_sorted_answers(outputs, expected)


def _sorted_in_amaranth(data_width: int, capacity: int, messages: list[Any], stall: float) -> tuple[list[Any], int]:
    from hetros.hw.nodes import NodeUnderTest, Sorter
    from hetros.hw.sim._sim import simulate

    codec = registry().codec("std_msgs/msg/UInt32MultiArray")
    bodies = []
    for message in messages:
        body = bytearray(codec.size(message))
        codec.encode(message, memoryview(body))
        bodies.append(bytes(body))
    node = NodeUnderTest(Sorter("/unsorted", "/sorted", data_width, capacity=capacity), ["unsorted"], ["sorted"],
                         data_width)
    result = simulate(node, [bodies], stall=stall, idle=0.2, seed=data_width)
    return [codec.decode(memoryview(body)) for body in result.received[0]], result.cycles


@pytest.mark.parametrize("data_width", [24, 32, 256])
def test_the_sorter_sorts_at_every_width_under_back_pressure(data_width: int) -> None:
    """Widths the Verilator test leaves out: a width that is not whole words (a byte a cycle), one word
    a beat, eight words a beat; the subscriber stalls 40 % of cycles."""
    messages, expected = _unsorted_arrays(data_width, [0, 1, 2, 3, 9, 31, 32, 17, 4, 30])
    outputs, _ = _sorted_in_amaranth(data_width, 32, messages, stall=0.4)
    _assert_sorted_answers(outputs, expected)


def test_the_sorter_moves_a_beat_a_cycle_and_merges_a_number_a_cycle() -> None:
    """512 numbers at 64 bits: 256 beats in, nine passes of 512 merge steps, 257 beats out, and a few
    cycles a pass to start: the pairs of a pass stream with no gap between them (the byte-a-cycle
    sorter took 2,048 cycles each way and a cycle more a pair)."""
    count = 512
    messages, expected = _unsorted_arrays(5, [count])
    outputs, cycles = _sorted_in_amaranth(64, count, messages, stall=0.0)
    _assert_sorted_answers(outputs, expected)
    least = count // 2 + 9 * count + (count + 3 + 1) // 2
    assert least <= cycles <= least + 10 * 9 + 64


def test_a_sorter_fed_past_its_capacity_by_hardware_sorts_the_numbers_it_kept() -> None:
    """Only software is checked before a message goes in; a hardware publisher can send more numbers
    than the block RAM holds: the first ``capacity`` are sorted, and nothing past them is written."""
    messages, _ = _unsorted_arrays(3, [40, 17, 16, 15, 3, 33])
    outputs, _ = _sorted_in_amaranth(64, 16, messages, stall=0.3)
    _assert_sorted_answers(outputs, [np.sort(np.asarray(message.data)[:16]) for message in messages])


def test_a_sorter_refuses_an_array_longer_than_its_block_ram() -> None:
    from hetros.hw.nodes import Sorter

    messages, _ = _unsorted_arrays(1, [65, 64])
    sorter = Sorter("/unsorted", "/sorted", 64, capacity=64)
    sorter._MustUse__silence = True  # checked in software only, never elaborated
    with pytest.raises(HardwareError, match=r"an array of 65 numbers is longer than the sorter's block RAM \(64 "
                                            r"numbers, its capacity parameter\): set capacity to at least 65"):
        sorter.check_message("/unsorted", messages[0])
    sorter.check_message("/unsorted", messages[1])


def test_a_verilog_node_names_what_its_module_lacks(tmp_path: Path) -> None:
    from hetros import CheckError

    source = (Path(__file__).resolve().parents[2] / "examples" / "ping_pong" / "rtl" / "echo_hls.v").read_text()
    (tmp_path / "echo.v").write_text(source.replace("output reg         recv_TLAST,", "").replace(
        "recv_TLAST <= send_TLAST;", ""))
    (tmp_path / "project.yaml").write_text(textwrap.dedent("""\
        name: broken
        targets: {io: {kind: process}, fpga: {kind: fpga}}
        nodes:
          ping: {run: json:dumps, target: io, publish: {/send: std_msgs/msg/String},
                 subscribe: {/recv: std_msgs/msg/String}}
          copy: {run: json:dumps, hw: "echo.v:echo_hls", target: fpga,
                 subscribe: {/send: std_msgs/msg/String}, publish: {/recv: std_msgs/msg/String}}
        """))
    with pytest.raises(CheckError, match=r"nodes\.copy\.hw: .*stream 'recv' lacks recv_tlast \(an AXI4-Stream port is "
                                         r"tdata, tkeep, tlast, tvalid and tready\)"):
        plan(load_project(tmp_path / "project.yaml"))
    (tmp_path / "echo.v").write_text(source.replace("[63:0] recv_TDATA", "[31:0] recv_TDATA"))
    with pytest.raises(CheckError, match=r"recv_TDATA is 32 bits \(\[31:0\]\), but must be 64 for the target's "
                                         r"data_width 64"):
        plan(load_project(tmp_path / "project.yaml"))


@pytest.mark.parametrize(("parameters", "error"), [
    ("", r"send_TDATA is 32 bits \(\[W-1:0\] with W = 32\), but must be 64 for the target's data_width 64: set "
         r"the module's parameters in the node's parameters"),
    ("parameters: {W: 64}", None),
    ("parameters: {W: 16}", r"send_TDATA is 16 bits \(\[W-1:0\] with W = 16\)"),
])
def test_a_verilog_nodes_port_widths_are_elaborated_with_its_parameters(tmp_path: Path, parameters: str,
                                                                       error: str | None) -> None:
    """``[W-1:0]`` is checked as the node elaborates it: the module's default, or the node's parameter."""
    from hetros import CheckError

    source = (Path(__file__).resolve().parents[2] / "examples" / "ping_pong" / "rtl" / "echo_hls.v").read_text()
    source = source.replace("#(parameter STAGES = 1)", "#(parameter STAGES = 1, parameter W = 32)")
    for port in ("send", "recv"):
        source = source.replace(f"[63:0] {port}_TDATA", f"[W-1:0] {port}_TDATA").replace(
            f"[7:0]  {port}_TKEEP", f"[W/8-1:0] {port}_TKEEP")
    (tmp_path / "echo.v").write_text(source)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""\
        name: widths
        targets: {{io: {{kind: process}}, fpga: {{kind: fpga}}}}
        nodes:
          ping: {{run: json:dumps, target: io, publish: {{/send: std_msgs/msg/String}},
                 subscribe: {{/recv: std_msgs/msg/String}}}}
          copy: {{run: json:dumps, hw: "echo.v:echo_hls", target: fpga, {parameters + "," if parameters else ""}
                 subscribe: {{/send: std_msgs/msg/String}}, publish: {{/recv: std_msgs/msg/String}}}}
        """))
    if error is None:
        plan(load_project(tmp_path / "project.yaml"))
    else:
        with pytest.raises(CheckError, match=error):
            plan(load_project(tmp_path / "project.yaml"))


@pytest.mark.parametrize(("text", "value"), [("W-1", 63), ("W/8-1", 7), ("$clog2(W)", 6), ("8'd16 * 2", 32),
                                             ("(W << 1) - 1", 127), ("-1 + W % 5", 3), ("8'hFF", 255)])
def test_verilog_constant_expressions_evaluate_as_elaboration_would(text: str, value: int) -> None:
    from hetros.hw.designs._verilog_node import constant

    assert constant(text, {"W": 64}) == value


def test_a_range_hetros_cannot_evaluate_is_named() -> None:
    from hetros import HardwareError
    from hetros.hw.designs._verilog_node import constant

    with pytest.raises(HardwareError, match="uses DEPTH, which hetros cannot evaluate"):
        constant("DEPTH-1", {"W": 64})
    with pytest.raises(HardwareError, match="cannot be evaluated"):
        constant("W / 0", {"W": 64})


def test_the_execution_models_of_a_chain_time_dataflow_against_sequential() -> None:
    """Blur -> Sobel: dataflow overlaps the two (about one frame's cycles), sequential adds them up and
    crosses the CPU twice more."""
    from hetros.hw.sim._models import execution_models, sample_message

    planned = plan(load_project(Path(__file__).resolve().parents[2] / "examples" / "sobel_hw" /
                                "project_chain_fpga.yaml"))
    types = registry()
    sample = sample_message(types, IMAGE, (64, 48), 0)
    dataflow, sequential = execution_models(planned, "fpga", types, {"/image_raw": sample})
    assert [name for name, _ in sequential.stages] == ["blur", "sobel"]
    assert 64 * 48 // 8 <= dataflow.cycles < 64 * 48 // 8 * 1.2
    assert sequential.cycles == sum(cycles for _, cycles in sequential.stages) > 1.8 * dataflow.cycles
    assert (dataflow.cpu_copies, sequential.cpu_copies) == (2, 4)


def test_the_vehicles_models_take_rgb8_and_check_each_output_against_the_twins() -> None:
    """`hw report --models` on the vehicle: an rgb8 frame (what its nodes are built for, channels: 3), and
    the hardware's every output held to the software twins; a twin that disagrees fails the timing."""
    from hetros import HardwareError
    from hetros.hw.designs import _image
    from hetros.hw.sim._models import channels_of, execution_models, sample_message

    planned = plan(load_project(Path(__file__).resolve().parents[2] / "examples" / "lane_following" /
                                "project_fpga.yaml"))
    types = registry()
    assert channels_of(planned, "fpga", "/image_raw") == 3
    sample = sample_message(types, IMAGE, (16, 12), 0, channels=3)
    assert (sample.encoding, sample.step, len(sample.data)) == ("rgb8", 48, 16 * 12 * 3)
    dataflow, sequential = execution_models(planned, "fpga", types, {"/image_raw": sample})
    assert dataflow.cycles < sequential.cycles
    original = _image.GaussianBlur.reference
    try:
        _image.GaussianBlur.reference = lambda self: (lambda image: image)  # type: ignore[method-assign]
        with pytest.raises(HardwareError, match=r"the hardware's /image_blur differs from its software twin in \d+ "
                                                r"of 576 bytes"):
            execution_models(planned, "fpga", types, {"/image_raw": sample})
    finally:
        _image.GaussianBlur.reference = original  # type: ignore[method-assign]


@pytest.mark.parametrize(("component", "twin", "data_width", "lanes"), [
    ("hetros.hw.nodes:GaussianBlur", gaussian_blur, 64, 1),
    ("hetros.hw.nodes:Compensation", None, 64, 1),
    ("hetros.hw.nodes:GaussianBlur", gaussian_blur, 64, 8),
    ("hetros.hw.nodes:Compensation", None, 64, 8),
    ("hetros.hw.nodes:Compensation", None, 256, 32),
])
@pytest.mark.slow
def test_rgb_filters_and_the_stateful_compensation_match_their_twins_frame_after_frame(
        tmp_path: Path, component: str, twin: Any, data_width: int, lanes: int) -> None:
    """rgb8 (a window per channel) over a stream of frames: the compensation stretches each frame with the
    percentiles of the one before, so its hardware must carry them from frame to frame as the twin does.
    At 32 lanes the histograms are summed over two more pipeline stages (in Amaranth's simulator, which
    builds a design this wide in seconds where Verilator takes a minute)."""
    from hetros.hw.reference import Compensation

    planned = _filter_project(tmp_path, component, data_width, sim="amaranth" if lanes > 8 else "verilator",
                              parameter=f"width: {max(24, lanes)}, channels: 3, lanes: {lanes}")
    apply = twin or Compensation()
    cls = registry().get(IMAGE)
    rng = np.random.default_rng(5)
    images, messages = [], []
    shapes = [(12, 24), (9, 17), (12, 24), (3, 3), (10, 20), (12, 24)] if lanes == 1 else \
        [(12, 24), (9, 16), (12, 24), (3, 8), (1, 8), (10, 16), (12, 24)] if lanes == 8 else \
        [(12, lanes), (9, lanes), (12, lanes), (3, lanes), (1, lanes), (10, lanes), (12, lanes)]
    for index, (height, width) in enumerate(shapes):
        image = rng.integers(0, 256, (height, width, 3), dtype=np.uint8)
        image[rng.random((height, width)) < 0.05] = 255  # outliers for the median
        image = (image // (1 + index % 3)).astype(np.uint8)  # a different spread each frame
        images.append(image)
        message = cls(height=height, width=width, encoding="rgb8", step=width * 3, data=image.reshape(-1))
        message.header.frame_id = "c" * index
        messages.append(message)
    outputs = _through_target(planned, messages)
    for image, output in zip(images, outputs, strict=True):
        np.testing.assert_array_equal(np.asarray(output.data).reshape(image.shape), apply(image))


def test_sim_amaranth_gives_verilators_bytes_and_cycles_behind_the_same_surface(tmp_path: Path) -> None:
    """The two simulators a target may name, on one design: the same output bytes, the same cycles per
    message at each gateway port, the same AXI4-Stream verdicts."""
    cls = registry().get(IMAGE)
    image = np.random.default_rng(11).integers(0, 256, (5, 8), dtype=np.uint8)
    message = cls(height=5, width=8, encoding="mono8", step=8, data=image.reshape(-1))
    seen = {}
    for sim in ("verilator", "amaranth"):
        folder = tmp_path / sim
        folder.mkdir()
        simulation = TargetSimulation(_filter_project(folder, "hetros.hw.nodes:Sobel", 32, width=8, sim=sim),
                                      "fpga", registry())
        try:
            (output,) = _through(simulation, [message])
            seen[sim] = (bytes(np.asarray(output.data)), simulation.top.stats(False, 0), simulation.top.stats(True, 0))
        finally:
            simulation.close()
    assert seen["verilator"] == seen["amaranth"]
    np.testing.assert_array_equal(np.frombuffer(seen["amaranth"][0], np.uint8).reshape(5, 8), sobel(image))
