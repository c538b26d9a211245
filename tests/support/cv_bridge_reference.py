"""Converts images with Debian's cv_bridge (ROS 1's, with OpenCV): read by /usr/bin/python3 from stdin as
JSON ({"images": [{"encoding", "height", "width", "step", "is_bigendian", "data" (hex)}], "conversions":
[[image index, desired encoding]]}), each result (dtype, shape, hex bytes) or error on stdout. The
reference hetros's cv_bridge is held against (tests/unit/test_cv_bridge.py); it imports nothing of hetros."""

import json
import sys

import cv_bridge
from sensor_msgs.msg import Image


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
    json.dump(answers, sys.stdout)


main()
