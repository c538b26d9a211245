"""The Debian side of benchmarks/libraries.py, run by /usr/bin/python3: ROS 1's tf2 (C++ core through its
Python binding), message_filters and cv_bridge on the scenario the bench sends as JSON on stdin; the best
seconds per operation of each case on stdout as JSON. Imports nothing of hetros."""

import json
import sys
import time

import numpy as np


def _best(run, repeat):
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        count = run()
        best = min(best, (time.perf_counter() - start) / count)
    return best


def tf_lookup(scenario):
    import rospy
    import tf2_py
    from geometry_msgs.msg import TransformStamped

    core = tf2_py.BufferCore(rospy.Duration(scenario["cache_s"]))
    for parent, child, ns, t, q in scenario["transforms"]:
        m = TransformStamped()
        m.header.frame_id, m.child_frame_id = parent, child
        m.header.stamp = rospy.Time(ns // 10**9, ns % 10**9)
        m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = t
        m.transform.rotation.x, m.transform.rotation.y, m.transform.rotation.z, m.transform.rotation.w = q
        core.set_transform(m, "bench")
    queries = [(a, b, rospy.Time(ns // 10**9, ns % 10**9)) for a, b, ns in scenario["queries"]]

    def run():
        for a, b, when in queries:
            core.lookup_transform_core(a, b, when)
        return len(queries)
    return _best(run, scenario["repeat"])


def approximate_sync(scenario):
    import message_filters
    import rospy.rostime
    from std_msgs.msg import Header

    rospy.rostime.set_rostime_initialized(True)

    class Stamped:
        __slots__ = ("header",)

        def __init__(self, ns):
            self.header = Header(stamp=rospy.Time(ns // 10**9, ns % 10**9))
    messages = [(index, Stamped(ns)) for index, ns in scenario["arrivals"]]

    def run():
        inputs = [message_filters.SimpleFilter() for _ in range(3)]
        sync = message_filters.ApproximateTimeSynchronizer(inputs, scenario["queue_size"], scenario["slop"])
        sync.registerCallback(lambda *msgs: None)
        for index, message in messages:
            inputs[index].signalMessage(message)
        return len(messages)
    return _best(run, scenario["repeat"])


def cv_bridge_read(scenario, desired):
    import cv_bridge

    bridge = cv_bridge.CvBridge()
    height, width = scenario["image"]
    message = bridge.cv2_to_imgmsg(np.random.default_rng(0).integers(0, 255, (height, width, 3), dtype=np.uint8),
                                   "rgb8")

    def run():
        for _ in range(50):
            bridge.imgmsg_to_cv2(message, desired)
        return 50
    return _best(run, scenario["repeat"])


def main():
    scenario = json.load(sys.stdin)
    json.dump({"tf_lookup": tf_lookup(scenario["tf"]), "approximate_sync": approximate_sync(scenario["sync"]),
               "cv_bridge_passthrough": cv_bridge_read(scenario["cv"], "passthrough"),
               "cv_bridge_mono8": cv_bridge_read(scenario["cv"], "mono8")}, sys.stdout)


main()
