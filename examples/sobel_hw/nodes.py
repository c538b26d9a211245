"""The papers' mixed graph: a software camera, a Sobel node, a software display.

The Sobel node has two implementations: ``sobel`` below (Python, numpy) and
``hetros.hw.nodes:Sobel`` (Amaranth: line buffers and a 3x3 window, a pixel a clock
cycle). ``project.yaml`` maps it to a process, so the Python runs; ``project_fpga.yaml``
maps it to an fpga target, so the hardware runs in Verilator behind gateways, and the
camera and display do not change. Both mappings write the same digests.

The ``project_chain*.yaml`` files put a Gaussian blur before the Sobel (fpgaDDS's execution
models): both in software; both on one fpga target, joined by a hardware topic (dataflow);
each on an fpga target of its own, the blurred image crossing through the CPU (sequential).
"""

import hashlib
from pathlib import Path

import numpy as np

from hetros import Node
from hetros.hw.reference import gaussian_blur
from hetros.hw.reference import sobel as sobel_edges
from hetros.interfaces.sensor_msgs.msg import Image


def frame(seq: int, height: int, width: int) -> np.ndarray:
    """A deterministic mono8 scene: a gradient, a bright box that moves, noise."""
    rng = np.random.default_rng(seq)
    y, x = np.mgrid[0:height, 0:width]
    img = ((x * 3 + y * 2 + seq * 5) % 256).astype(np.uint8)
    top, left = (seq * 3) % max(1, height // 2), (seq * 5) % max(1, width // 2)
    img[top:top + height // 3, left:left + width // 3] = 250
    noisy: np.ndarray = np.clip(img.astype(np.int16) + rng.integers(0, 12, img.shape), 0, 255).astype(np.uint8)
    return noisy


def camera(node: Node) -> None:
    height, width = node.get_parameter("height"), node.get_parameter("width")
    pub = node.create_publisher(Image, "/image_raw")
    for seq in node.rate(node.get_parameter("hz", 20.0)):
        if seq >= node.get_parameter("frames"):
            return
        msg = pub.loan(data=height * width)  # a large frame is drawn straight into its shared-memory slot
        msg.data.reshape(height, width)[:] = frame(seq, height, width)
        msg.height, msg.width, msg.encoding, msg.step = height, width, "mono8", width
        msg.header.frame_id = f"frame{seq}"
        pub.publish(msg)


FILTERS = {"sobel": sobel_edges, "blur": gaussian_blur}


def _filter(node: Node, name: str, source: str, sink: str) -> None:
    """One filter stage, from ``source`` to ``sink`` (the hardware twin gets the same names as parameters)."""
    apply = FILTERS[name]
    pub = node.create_publisher(Image, sink)

    def on_image(msg: Image) -> None:
        filtered = apply(msg.data.reshape(msg.height, msg.width))
        pub.publish(Image(header=msg.header, height=msg.height, width=msg.width, encoding=msg.encoding,
                          is_bigendian=msg.is_bigendian, step=msg.step, data=filtered.reshape(-1)))

    node.create_subscription(Image, source, on_image)
    node.spin()


def sobel(node: Node) -> None:
    _filter(node, "sobel", "/image_raw", "/image_edges")


def blur(node: Node) -> None:
    """The chain's first stage."""
    _filter(node, "blur", "/image_raw", "/image_blur")


def chained_sobel(node: Node) -> None:
    """The chain's second stage."""
    _filter(node, "sobel", "/image_blur", "/image_edges")


def display(node: Node) -> None:
    """Checks each frame against the software filters (``pipeline``, Sobel alone by default) and writes one
    digest line per frame."""
    frames = node.get_parameter("frames")
    height, width = node.get_parameter("height"), node.get_parameter("width")
    pipeline = [FILTERS[name] for name in node.get_parameter("pipeline", ["sobel"])]
    lines = []
    sub = node.create_subscription(Image, "/image_edges")
    for _ in range(frames):
        msg = sub.take()
        seq = int(msg.header.frame_id.removeprefix("frame"))
        expected = frame(seq, height, width)
        for stage in pipeline:
            expected = stage(expected)
        got = msg.data.reshape(msg.height, msg.width)
        if not np.array_equal(got, expected):
            wrong = np.argwhere(got != expected)
            raise ValueError(f"frame {seq}: {len(wrong)} pixels differ from the software filters, first at {wrong[0]}")
        lines.append(f"{msg.header.frame_id} {msg.width}x{msg.height} {msg.encoding} "
                     f"{hashlib.sha256(got.tobytes()).hexdigest()[:16]}")
    out = Path(node.get_parameter("out", "out/sobel_hw"))
    out.mkdir(parents=True, exist_ok=True)
    (out / "edges.txt").write_text("\n".join(lines) + "\n")
    node.log.info("%d frames, every pixel equal to the software filters; digests in %s", frames, out / "edges.txt")
