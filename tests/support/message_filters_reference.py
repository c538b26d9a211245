"""Runs message arrivals through Debian's message_filters (ROS 1's Python library): read by
/usr/bin/python3 from stdin as JSON ({"kind", "queue_size", "slop", "inputs", "arrivals": [[input, ns]]}),
the stamps of every emitted set on stdout as JSON. The reference hetros's synchronizers are held against
(tests/unit/test_message_filters.py); it imports nothing of hetros."""

import json
import sys

import message_filters
import rospy
import rospy.rostime
from std_msgs.msg import Header

rospy.rostime.set_rostime_initialized(True)  # rospy.Time.now() without a master: the wall clock


class Stamped:
    def __init__(self, ns):
        self.header = Header(stamp=rospy.Time(ns // 1_000_000_000, ns % 1_000_000_000))


def main():
    scenario = json.load(sys.stdin)
    inputs = [message_filters.SimpleFilter() for _ in range(scenario["inputs"])]
    if scenario["kind"] == "approximate":
        sync = message_filters.ApproximateTimeSynchronizer(inputs, scenario["queue_size"], scenario["slop"])
    else:
        sync = message_filters.TimeSynchronizer(inputs, scenario["queue_size"])
    emitted = []
    sync.registerCallback(lambda *msgs: emitted.append([m.header.stamp.to_nsec() for m in msgs]))
    for index, ns in scenario["arrivals"]:
        inputs[index].signalMessage(Stamped(ns))
    json.dump(emitted, sys.stdout)


main()
