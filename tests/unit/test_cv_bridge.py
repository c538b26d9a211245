"""cv_bridge for rclpy and rospy code (``hetros.compat.cv_bridge``): every encoding round-trips bit for
bit and reads as Debian's cv_bridge reads it; conversions between mono/rgb/bgr/rgba/bgra at 8 and 16 bits
give Debian's bytes (OpenCV's arithmetic); an image in its own encoding is a view of the message, padded
rows included, never a copy; what cannot be read is named."""

from __future__ import annotations

import importlib.util
import json
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hetros.compat.cv_bridge import CvBridge, CvBridgeError, encoding_layout
from hetros.msg import registry

REFERENCE = Path(__file__).resolve().parents[1] / "support" / "cv_bridge_reference.py"
_HAS_REFERENCE = Path("/usr/bin/python3").exists() and subprocess.run(
    ["/usr/bin/python3", "-c", "import cv_bridge"], capture_output=True, check=False).returncode == 0
_HAS_OPENCV = importlib.util.find_spec("cv2") is not None
NAMED = ["mono8", "mono16", "rgb8", "bgr8", "rgba8", "bgra8", "rgb16", "bgr16", "rgba16", "bgra16", "bayer_rggb8",
         "bayer_bggr8", "bayer_gbrg8", "bayer_grbg8", "bayer_rggb16", "yuv422", "yuv422_yuy2"]
GENERIC = [f"{depth}C{n}" for depth in ("8U", "8S", "16U", "16S", "32S", "32F", "64F") for n in (1, 2, 3, 4)]
COLOURS = ["mono8", "mono16", "rgb8", "bgr8", "rgba8", "bgra8", "rgb16", "bgr16", "rgba16", "bgra16"]


def _image(encoding: str, seed: int, height: int = 5, width: int = 7) -> np.ndarray:
    dtype, channels = encoding_layout(encoding)
    rng = np.random.default_rng(seed)
    shape = (height, width) if channels == 1 else (height, width, channels)
    if dtype.kind == "f":
        return rng.normal(0, 100, shape).astype(dtype)
    info = np.iinfo(dtype)
    return rng.integers(info.min, info.max, shape, dtype=dtype, endpoint=True)


@pytest.mark.parametrize("encoding", NAMED + GENERIC)
def test_every_encoding_round_trips_bit_for_bit_as_a_view(encoding: str) -> None:
    bridge = CvBridge()
    image = _image(encoding, 3)
    message = bridge.cv2_to_imgmsg(image, encoding)
    assert message.encoding == encoding and message.step == image.shape[1] * image[0, 0].nbytes
    back = bridge.imgmsg_to_cv2(message)
    assert back.dtype == image.dtype and np.array_equal(back, image, equal_nan=image.dtype.kind == "f")
    assert np.shares_memory(back, message.data)  # a view of the message, not a copy


def test_padded_rows_are_skipped_by_the_view() -> None:
    bridge = CvBridge()
    image = _image("rgb8", 4)
    padded = np.zeros((5, 7 * 3 + 11), np.uint8)
    padded[:, :21] = image.reshape(5, 21)
    message = registry().get("sensor_msgs/msg/Image")(height=5, width=7, encoding="rgb8", step=32,
                                                      data=padded.reshape(-1))
    back = bridge.imgmsg_to_cv2(message)
    assert np.array_equal(back, image) and np.shares_memory(back, message.data)
    message.data = message.data[:100]
    with pytest.raises(CvBridgeError, match="too few for 5 rows of step 32"):
        bridge.imgmsg_to_cv2(message)


@pytest.mark.parametrize(("make", "words"), [
    (lambda b: b.cv2_to_imgmsg(np.zeros((2, 2, 3), np.uint8), "mono8"), "incompatible type 8UC3"),
    (lambda b: b.cv2_to_imgmsg(np.zeros((2, 2), np.uint8), "nonsense"), "Unrecognized image encoding"),
    (lambda b: b.cv2_to_imgmsg(np.zeros((2, 2), np.complex64)), "an image's type must be one of"),
    (lambda b: b.imgmsg_to_cv2(b.cv2_to_imgmsg(np.zeros((2, 2), np.float32)), "mono8"), "is not a color format"),
])
def test_what_cannot_be_converted_is_named(make: Any, words: str) -> None:
    with pytest.raises(CvBridgeError, match=words):
        make(CvBridge())


@pytest.mark.skipif(not _HAS_REFERENCE, reason="Debian's python3-cv-bridge is not installed")
def test_reads_and_conversions_equal_debians_cv_bridge() -> None:
    bridge = CvBridge()
    encodings = NAMED + GENERIC
    messages = [bridge.cv2_to_imgmsg(_image(encoding, index, 6, 8), encoding)
                for index, encoding in enumerate(encodings)]
    conversions = [[i, "passthrough"] for i in range(len(encodings))]
    conversions += [[encodings.index(src), dst] for src in COLOURS for dst in COLOURS if src != dst]
    scenario = {"images": [{"encoding": m.encoding, "height": m.height, "width": m.width, "step": m.step,
                            "is_bigendian": int(m.is_bigendian), "data": bytes(m.data).hex()} for m in messages],
                "conversions": conversions}
    done = subprocess.run(["/usr/bin/python3", str(REFERENCE)], input=json.dumps(scenario), capture_output=True,
                          text=True, check=True, timeout=120)
    for (index, desired), want in zip(conversions, json.loads(done.stdout)["conversions"], strict=True):
        if encodings[index] == "yuv422_yuy2":  # newer than Debian's cv_bridge (1.16), which does not know it
            assert want == {"error": "Unrecognized image encoding [yuv422_yuy2]"}
            continue
        assert "error" not in want, (encodings[index], desired, want)
        got = bridge.imgmsg_to_cv2(messages[index], desired)
        assert (got.dtype.name, list(got.shape)) == (want["dtype"], want["shape"]), (encodings[index], desired)
        assert got.astype(got.dtype.newbyteorder("<")).tobytes().hex() == want["data"], (encodings[index], desired)


@pytest.mark.skipif(not _HAS_REFERENCE or not _HAS_OPENCV, reason="needs Debian's python3-cv-bridge and OpenCV "
                    "(opencv-python-headless, which `make test` installs)")
def test_what_needs_opencv_equals_debians_cv_bridge() -> None:
    """Bayer demosaicing and YUV 4:2:2 (OpenCV's, where installed) give Debian's bytes; a lossless compressed
    image made on either side reads back on the other as the image it was."""
    bridge = CvBridge()
    sources = ["bayer_rggb8", "bayer_bggr8", "bayer_gbrg8", "bayer_grbg8", "bayer_rggb16", "yuv422"]
    targets = {"bayer_rggb16": ["bgr16", "rgb16", "mono16"], "yuv422": ["bgr8", "rgb8"]}
    messages = [bridge.cv2_to_imgmsg(_image(encoding, 40 + index, 8, 10), encoding)
                for index, encoding in enumerate(sources)]
    conversions = [[i, dst] for i, src in enumerate(sources) for dst in targets.get(src, ["bgr8", "rgb8", "mono8"])]
    plain = [bridge.cv2_to_imgmsg(_image(encoding, 60 + index, 9, 11), encoding)
             for index, encoding in enumerate(["mono8", "bgr8", "mono16", "bgra8"])]
    images = messages + plain
    compress = [[len(messages) + i, "png"] for i in range(len(plain))]
    ours = [bridge.cv2_to_compressed_imgmsg(bridge.imgmsg_to_cv2(m), "png") for m in plain]
    scenario = {"images": [{"encoding": m.encoding, "height": m.height, "width": m.width, "step": m.step,
                            "is_bigendian": int(m.is_bigendian), "data": bytes(m.data).hex()} for m in images],
                "conversions": conversions, "compress": compress,
                "decode": [{"format": c.format, "data": bytes(c.data).hex()} for c in ours]}
    done = subprocess.run(["/usr/bin/python3", str(REFERENCE)], input=json.dumps(scenario), capture_output=True,
                          text=True, check=True, timeout=120)
    answer = json.loads(done.stdout)
    for (index, desired), want in zip(conversions, answer["conversions"], strict=True):
        assert "error" not in want, (sources[index], desired, want)
        got = bridge.imgmsg_to_cv2(images[index], desired)
        assert (got.dtype.name, list(got.shape)) == (want["dtype"], want["shape"]), (sources[index], desired)
        assert got.astype(got.dtype.newbyteorder("<")).tobytes().hex() == want["data"], (sources[index], desired)
    for message, theirs, back in zip(plain, answer["compressed"], answer["decoded"], strict=True):
        original = bridge.imgmsg_to_cv2(message)
        packed = registry().get("sensor_msgs/msg/CompressedImage")(format=theirs["format"],
                                                                 data=bytes.fromhex(theirs["data"]))
        assert np.array_equal(bridge.compressed_imgmsg_to_cv2(packed), original), message.encoding
        assert (back["dtype"], back["shape"]) == (original.dtype.name, list(original.shape)), message.encoding
        assert back["data"] == original.tobytes().hex(), message.encoding
