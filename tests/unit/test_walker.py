"""The authoring kit's field walker: generated per type, held to its slow reference (``label_bytes``),
the reference to bytes annotated by hand, and a node on one field of an Image in a few lines."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("amaranth")

from amaranth import Module, Mux
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from hetros import HardwareError
from hetros.hw.nodes import FieldWalker, NodeUnderTest, axi_stream, label_bytes
from hetros.hw.sim._sim import simulate
from hetros.msg import registry
from tests.support.messages import cdr_body

TYPES = registry()


def _body(typename: str, message: Any) -> bytes:
    return cdr_body(TYPES, typename, message)


def _walk(typename: str) -> Any:
    """The walk of a walker that is only asked (never elaborated)."""
    walker = FieldWalker(typename)
    walker._MustUse__silence = True
    return walker.walk


def test_a_navsatfix_labelled_by_hand() -> None:
    """frame_id "gps" (length 4 with its NUL), then the status's int8 and uint16 (a byte of padding between),
    4 bytes of padding before the float64s (the offset is known only at run time after a string)."""
    fix = TYPES.get("sensor_msgs/msg/NavSatFix")(latitude=52.5)
    fix.header.frame_id = "gps"
    labels = label_bytes(_walk("sensor_msgs/msg/NavSatFix"), _body("sensor_msgs/msg/NavSatFix", fix))
    expected = ([("header.stamp.sec", i, False) for i in range(4)]
                + [("header.stamp.nanosec", i, False) for i in range(4)]
                + [("header.frame_id", i, True) for i in range(4)] + [("header.frame_id", i, False) for i in range(4)]
                + [("status.status", 0, False), ("(padding)", 0, False)]
                + [("status.service", i, False) for i in range(2)] + [("(padding)", 0, False)] * 4
                + [(name, i, False) for name in ("latitude", "longitude", "altitude") for i in range(8)]
                + [("position_covariance", i, False) for i in range(72)] + [("position_covariance_type", 0, False)])
    assert [(label.field, label.index, label.length) for label in labels] == expected


def _messages() -> dict[str, list[Any]]:
    image, scan = TYPES.get("sensor_msgs/msg/Image"), TYPES.get("sensor_msgs/msg/LaserScan")
    fix = TYPES.get("sensor_msgs/msg/NavSatFix")
    rng = np.random.default_rng(0)
    found: dict[str, list[Any]] = {"sensor_msgs/msg/Image": [], "sensor_msgs/msg/LaserScan": [],
                                   "sensor_msgs/msg/NavSatFix": []}
    for i in range(5):  # every alignment after the strings; empty and short sequences
        picture = image(height=2, width=3 + i, encoding="rgb8"[:i + 1], step=3 + i,
                        data=rng.integers(0, 256, 2 * (3 + i), dtype=np.uint8))
        picture.header.frame_id = "x" * i
        ranges = scan(ranges=rng.random(i).astype(np.float32), intensities=rng.random(max(0, 3 - i)).astype(np.float32))
        ranges.header.frame_id = "ab" * i
        place = fix(latitude=1.5 * i, position_covariance=np.arange(9, dtype=np.float64))
        place.header.frame_id = "q" * i
        for typename, message in zip(found, (picture, ranges, place), strict=True):
            found[typename].append(message)
    return found


class _Stamp(wiring.Component):
    """Every byte replaced by what the walker says of it: its field (bit 7: a length's) or its index."""

    def __init__(self, typename: str, data_width: int, what: str) -> None:
        self.walker, self.what = FieldWalker(typename, data_width), what
        super().__init__({"a": In(axi_stream(data_width)), "b": Out(axi_stream(data_width))})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        m.submodules.walker = walker = self.walker
        wiring.connect(m, wiring.flipped(self.a), walker.cdr_in)
        wiring.connect(m, walker.cdr_out, wiring.flipped(self.b))
        said = walker.field | (walker.length << 7) if self.what == "field" else walker.index[:8]
        m.d.comb += [walker.replace.eq(1), walker.replacement.eq(said)]
        return m


@pytest.mark.parametrize("data_width", [8, 64])
@pytest.mark.parametrize("typename", sorted(_messages()))
def test_the_walker_names_every_byte_as_the_reference_does(typename: str, data_width: int) -> None:
    """Messages back to back, idle and stalled cycles at random."""
    bodies = [_body(typename, message) for message in _messages()[typename]]
    walk = _walk(typename)
    for what in ("field", "index"):
        result = simulate(NodeUnderTest(_Stamp(typename, data_width, what), ["a"], ["b"], data_width), [bodies],
                          stall=0.3, idle=0.3, seed=1)
        for body, got in zip(bodies, result.received[0], strict=True):
            labels = label_bytes(walk, body)
            said = [walk.fields.index(label.field) | (label.length << 7) if what == "field" else label.index % 256
                    for label in labels]
            assert got == bytes(said)


class _ImageThreshold(wiring.Component):
    """A kit node on one field: the pixels of an Image thresholded, everything else as it came."""

    def __init__(self, data_width: int, level: int) -> None:
        self.walker, self.level = FieldWalker("sensor_msgs/msg/Image", data_width), level
        super().__init__({"raw": In(axi_stream(data_width)), "mask": Out(axi_stream(data_width))})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        m.submodules.walker = walker = self.walker
        wiring.connect(m, wiring.flipped(self.raw), walker.cdr_in)
        wiring.connect(m, walker.cdr_out, wiring.flipped(self.mask))
        pixel = (walker.field == walker.field_index("data")) & ~walker.length
        m.d.comb += [walker.replace.eq(pixel), walker.replacement.eq(Mux(walker.byte >= self.level, 255, 0))]
        return m


def _guide_image_threshold() -> type[Any]:
    """The field walker's example node of the FPGA guide (docs/GUIDE.md), as the guide prints it."""
    guide = (Path(__file__).resolve().parents[2] / "docs" / "GUIDE.md").read_text()
    code = guide.split("starts from the **field walker**", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    assert len(code.strip().splitlines()) < 40
    scope: dict[str, Any] = {}
    exec(compile(code, "GUIDE.md", "exec"), scope)
    return scope["ImageThreshold"]  # type: ignore[no-any-return]


@pytest.mark.parametrize("node", ["test", "guide"])
def test_a_node_on_one_field_is_a_comparison_and_a_value(node: str) -> None:
    """The test's node and the guide's, on images of every frame_id length: header and strings as they came."""
    made = _ImageThreshold(64, 100) if node == "test" else _guide_image_threshold()("/raw", "/mask", 64, 100)
    image = TYPES.get("sensor_msgs/msg/Image")
    rng = np.random.default_rng(4)
    messages = []
    for i in range(4):
        message = image(height=3, width=5 + i, encoding="mono8", step=5 + i,
                        data=rng.integers(0, 256, 3 * (5 + i), dtype=np.uint8))
        message.header.frame_id = "camera"[:i + 2]
        messages.append(message)
    result = simulate(NodeUnderTest(made, ["raw"], ["mask"], 64),
                      [[_body("sensor_msgs/msg/Image", m) for m in messages]], stall=0.2, seed=3)
    codec = TYPES.codec("sensor_msgs/msg/Image")
    for message, body in zip(messages, result.received[0], strict=True):
        out = codec.decode(memoryview(body))
        assert (out.header.frame_id, out.width, out.encoding) == (message.header.frame_id, message.width, "mono8")
        np.testing.assert_array_equal(np.asarray(out.data), np.where(np.asarray(message.data) >= 100, 255, 0))


def test_what_a_walker_cannot_name_is_refused_with_the_field() -> None:
    with pytest.raises(HardwareError, match=r"name is a sequence of strings: the field walker names the bytes of "
                                            r"sequences of numbers only"):
        FieldWalker("sensor_msgs/msg/JointState")
    with pytest.raises(HardwareError, match=r"sensor_msgs/msg/Image has no field 'pixels' a walker names; its "
                                            r"fields are: header.stamp.sec, .*, data"):
        _walk("sensor_msgs/msg/Image").field_index("pixels")
