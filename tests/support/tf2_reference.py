"""Runs a transform scenario through Debian's tf2 (ROS 1's C++ BufferCore, by its Python binding): read
by /usr/bin/python3 from stdin as JSON, answered on stdout as JSON. The reference hetros's tree is held
against (tests/unit/test_tf2_reference.py); it imports nothing of hetros."""

import json
import sys

import rospy
import tf2_py
from geometry_msgs.msg import TransformStamped


def _time(ns):
    return rospy.Time(ns // 1_000_000_000, ns % 1_000_000_000)


def _message(item):
    message = TransformStamped()
    message.header.frame_id, message.child_frame_id = item["parent"], item["child"]
    message.header.stamp = _time(item["stamp"])
    t, r = message.transform.translation, message.transform.rotation
    t.x, t.y, t.z = item["translation"]
    r.x, r.y, r.z, r.w = item["rotation"]
    return message


def _answer(call):
    try:
        out = call()
    except tf2_py.TransformException as exc:
        return {"error": type(exc).__name__, "text": str(exc)}
    t, r = out.transform.translation, out.transform.rotation
    return {"translation": [t.x, t.y, t.z], "rotation": [r.x, r.y, r.z, r.w],
            "stamp": out.header.stamp.secs * 1_000_000_000 + out.header.stamp.nsecs}


def main():
    scenario = json.load(sys.stdin)
    core = tf2_py.BufferCore(rospy.Duration(scenario["cache_s"]))
    for item in scenario["transforms"]:
        (core.set_transform_static if item["static"] else core.set_transform)(_message(item), "reference")
    answers = []
    for query in scenario["queries"]:
        if "fixed" in query:
            answers.append(_answer(lambda q=query: core.lookup_transform_full_core(
                q["target"], _time(q["target_time"]), q["source"], _time(q["time"]), q["fixed"])))
        else:
            answers.append(_answer(lambda q=query: core.lookup_transform_core(q["target"], q["source"],
                                                                               _time(q["time"]))))
    json.dump(answers, sys.stdout)


main()
