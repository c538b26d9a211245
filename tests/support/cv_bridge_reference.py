"""Converts images with Debian's cv_bridge (ROS 1's, with OpenCV): read by /usr/bin/python3 from stdin as
JSON ({"images": [{"encoding", "height", "width", "step", "is_bigendian", "data" (hex)}], "conversions":
[[image index, desired encoding]], "compress": [[image index, format]], "decode": [{"format", "data"}]}), each
result (dtype, shape, hex bytes) or error on stdout. The
reference hetros's cv_bridge is held against (tests/unit/test_cv_bridge.py); it imports nothing of hetros."""

import json
import sys

import cv_bridge
from sensor_msgs.msg import CompressedImage, Image


def main():
    scenario = json.load(sys.stdin)
    bridge = cv_bridge.CvBridge()
    images = []
    for given in scenario["images"]:
        message = Image(height=given["height"], width=given["width"], encoding=given["encoding"],
                        is_bigendian=given["is_bigendian"], step=given["step"])
        message.data = bytes.fromhex(given["data"])
        images.append(message)
    answers = []
    for index, desired in scenario["conversions"]:
        try:
            out = bridge.imgmsg_to_cv2(images[index], desired)
        except cv_bridge.CvBridgeError as exc:
            answers.append({"error": str(exc)})
            continue
        out = out.astype(out.dtype.newbyteorder("<"))
        answers.append({"dtype": out.dtype.name, "shape": list(out.shape), "data": out.tobytes().hex()})
    compressed = []
    for index, fmt in scenario.get("compress", []):  # Debian's compressed image of an image, decoded back
        packed = bridge.cv2_to_compressed_imgmsg(bridge.imgmsg_to_cv2(images[index]), fmt)
        compressed.append({"format": packed.format, "data": bytes(packed.data).hex()})
    decoded = []
    for given in scenario.get("decode", []):  # a compressed image hetros made, read by Debian's cv_bridge
        message = CompressedImage(format=given["format"])
        message.data = bytes.fromhex(given["data"])
        out = bridge.compressed_imgmsg_to_cv2(message)
        decoded.append({"dtype": out.dtype.name, "shape": list(out.shape), "data": out.tobytes().hex()})
    json.dump({"conversions": answers, "compressed": compressed, "decoded": decoded}, sys.stdout)


main()
