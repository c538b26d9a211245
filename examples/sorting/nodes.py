"""ReconROS's number sorting: 2048 random uint32 sorted by odd-even transposition.

The algorithm is the hardware one (a fixed network of compare-exchange stages, n
phases alternating even and odd pairs), vectorised: each phase is one numpy
minimum/maximum over all its pairs. The generator node checks every result
against ``numpy.sort``.
"""

import numpy as np

from hetros import Node
from hetros.interfaces.std_msgs.msg import UInt32MultiArray


def odd_even_transposition_sort(values: np.ndarray) -> np.ndarray:
    """Sort with n phases of parallel compare-exchange (odd-even transposition)."""
    data = np.array(values, copy=True)
    n = data.size
    for phase in range(n):
        start = phase % 2
        stop = n - (n - start) % 2
        left, right = data[start:stop:2], data[start + 1:stop:2]
        low, high = np.minimum(left, right), np.maximum(left, right)
        data[start:stop:2], data[start + 1:stop:2] = low, high
    return data


def generator(node: Node) -> None:
    pub = node.create_publisher(UInt32MultiArray, "/unsorted")
    sub = node.create_subscription(UInt32MultiArray, "/sorted")
    rng = np.random.default_rng(node.get_parameter("seed", 1))
    size = node.get_parameter("size", 2048)
    for run in range(node.get_parameter("runs", 5)):
        values = rng.integers(0, 2**32, size, dtype=np.uint32)
        pub.publish(UInt32MultiArray(data=values.copy()))
        result = sub.take(timeout=30.0)
        if not np.array_equal(result.data, np.sort(values)):
            raise ValueError(f"run {run}: the sorter's result differs from numpy.sort")
        node.log.info("run %d: %d numbers sorted correctly (min %d, max %d)", run, size,
                      result.data[0], result.data[-1])


def sorter(node: Node) -> None:
    pub = node.create_publisher(UInt32MultiArray, "/sorted")
    for msg in node.create_subscription(UInt32MultiArray, "/unsorted"):
        pub.publish(UInt32MultiArray(data=odd_even_transposition_sort(msg.data)))
