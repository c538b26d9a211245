"""Nodes of the hardware-topic example: their software ``run`` only, until hardware nodes exist.

On an fpga target, a node is a hardware thread in the making: `hetros hw build` generates
the AXI-Stream network its topics need; the functions here are what the nodes do in
software (and what a gateway will later compare against).
"""

import numpy as np

from hetros import Node
from hetros.interfaces.hw_msgs.msg import Features
from hetros.interfaces.sensor_msgs.msg import Image


def camera(node: Node) -> None:
    pub = node.create_publisher(Image, "/image")
    for _ in node.rate(10):
        pub.publish(Image(height=2, width=2, encoding="mono8", step=2, data=np.arange(4, dtype=np.uint8)))


def filter_a(node: Node) -> None:
    pub = node.create_publisher(Features, "/features")
    for image in node.create_subscription(Image, "/image"):
        pub.publish(Features(frame=image.header.stamp.sec, values=np.asarray(image.data, np.uint32)))


def filter_b(node: Node) -> None:
    pub = node.create_publisher(Features, "/features")
    for image in node.create_subscription(Image, "/image"):
        pub.publish(Features(frame=image.header.stamp.sec, values=np.asarray(image.data, np.uint32)[::-1].copy()))


def sink(node: Node) -> None:
    for features in node.create_subscription(Features, "/features"):
        node.log.info("%d features", len(features.values))
