"""The rospy peer of the latency benchmark (TCPROS through a Debian rosmaster).

Runs under the system interpreter (/usr/bin/python3), where Debian's rospy lives,
so it imports nothing from hetros; the protocol matches ``_roles``: a 16-byte
prefix (stamp, sequence number) in a std_msgs/UInt8MultiArray.
"""

import json
import os
import queue
import struct
import sys
import time

PREFIX = struct.Struct("<qq")
PROBE = -1
STOP = -2


def main():
    role, cfg_path = sys.argv[1], sys.argv[2]
    with open(cfg_path) as handle:
        cfg = json.load(handle)
    if cfg.get("cpus"):
        os.sched_setaffinity(0, [cfg["cpus"][0 if role == "ping" else 1]])
    import rospy
    from std_msgs.msg import UInt8MultiArray

    rospy.init_node("bench_" + role, anonymous=False, disable_signals=True)
    inbox = queue.Queue()
    out_topic, in_topic = ("/bench_send", "/bench_recv") if role == "ping" else ("/bench_recv", "/bench_send")
    pub = rospy.Publisher(out_topic, UInt8MultiArray, queue_size=16, tcp_nodelay=True)
    rospy.Subscriber(in_topic, UInt8MultiArray, lambda m: inbox.put((time.monotonic_ns(), m.data)),
                     queue_size=16, tcp_nodelay=True)

    def send(stamp, seq, payload):
        pub.publish(UInt8MultiArray(data=PREFIX.pack(stamp, seq) + payload))

    def recv(timeout):
        try:
            arrival, data = inbox.get(timeout=timeout)
        except queue.Empty:
            return None
        stamp, seq = PREFIX.unpack_from(data)
        return arrival, stamp, seq, data

    result = {}
    if role == "ping":
        payload = bytes(cfg["size"])
        deadline = time.monotonic() + 60
        while True:
            send(time.monotonic_ns(), PROBE, payload)
            if recv(0.2) is not None:
                break
            if time.monotonic() > deadline:
                raise SystemExit("rospy: the echo side never answered")
        while recv(0.1) is not None:
            pass
        rtt = []
        for seq in range(cfg["warmup"] + cfg["reps"]):
            settled = time.monotonic() + cfg.get("settle_s", 0.0)
            while time.monotonic() < settled:  # awake: the echo finishes its reply, this CPU stays warm
                pass
            start = time.monotonic_ns()
            send(start, seq, payload)
            while True:
                got = recv(10.0)
                if got is None:
                    raise SystemExit(f"rospy: reply {seq} lost")
                if got[2] == seq:
                    break
            if seq >= cfg["warmup"]:
                rtt.append(time.monotonic_ns() - start)
            if cfg.get("gap_s"):
                time.sleep(cfg["gap_s"])
        send(time.monotonic_ns(), STOP, b"")
        time.sleep(0.2)
        result["rtt_ns"] = rtt
    else:
        one_way = []
        while True:
            got = recv(120.0)
            if got is None:
                raise SystemExit("rospy: echo waited 120 s")
            arrival, stamp, seq, data = got
            if seq == STOP:
                break
            if seq >= cfg["warmup"]:
                one_way.append(arrival - stamp)
            pub.publish(UInt8MultiArray(data=bytes(data)))
        result["one_way_ns"] = one_way
    with open(cfg[role + "_out"], "w") as handle:
        json.dump(result, handle)
    os._exit(0)


if __name__ == "__main__":
    main()
