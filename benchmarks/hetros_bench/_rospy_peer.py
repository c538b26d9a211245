"""The rospy peer of the latency benchmarks (TCPROS through a Debian rosmaster).

Runs under the system interpreter (/usr/bin/python3), where Debian's rospy lives,
so it imports nothing from hetros: the protocol it shares with ``_ros1_nodes`` is
``_ros1_protocol`` beside it (standard library only). In ``serve`` mode an echo keeps
one-way samples per sender tag, writes them all at every STOP, and runs until killed;
otherwise it stops at the first STOP (``latency.py``'s rospy rows, one sender, tag 0).
"""

import json
import os
import queue
import sys
import time

# the script's folder is on sys.path: the protocol module beside it, without hetros
from _ros1_protocol import COUNT, PREFIX, PROBE, STOP, TAG_SHIFT, measured, open_turns, reply_topic, write_result


def main():
    role, cfg_path = sys.argv[1], sys.argv[2]
    with open(cfg_path) as handle:
        cfg = json.load(handle)
    if cfg.get("cpus"):
        os.sched_setaffinity(0, [cfg["cpus"][0 if role == "ping" else 1]])
    import rospy
    from std_msgs.msg import UInt8MultiArray

    tag = cfg.get("tag", 0)
    rospy.init_node(f"bench_{role}{tag or ''}", anonymous=False, disable_signals=True)
    inbox = queue.Queue()
    if role == "ping":
        pubs = {tag: rospy.Publisher("/bench_send", UInt8MultiArray, queue_size=16, tcp_nodelay=True)}
        into = reply_topic(tag)
    else:
        pubs = {t: rospy.Publisher(reply_topic(t), UInt8MultiArray, queue_size=16, tcp_nodelay=True)
                for t in cfg.get("tags", [0])}
        into = "/bench_send"
    rospy.Subscriber(into, UInt8MultiArray, lambda m: inbox.put((time.monotonic_ns(), m.data)),
                     queue_size=16, tcp_nodelay=True)

    def recv(timeout):
        try:
            arrival, data = inbox.get(timeout=timeout)
        except queue.Empty:
            return None
        stamp, seq = PREFIX.unpack_from(data)
        return arrival, stamp, seq, data

    if role == "ping":
        pub = pubs[tag]
        top = tag << TAG_SHIFT

        def send(count, payload):
            stamp = time.monotonic_ns()
            pub.publish(UInt8MultiArray(data=PREFIX.pack(stamp, top | count) + payload))
            return stamp

        payload = bytes(cfg["size"])
        deadline = time.monotonic() + 60
        while True:
            send(PROBE, payload)
            if recv(0.2) is not None:
                break
            if time.monotonic() > deadline:
                raise SystemExit("rospy: the echo side never answered")
        while recv(0.1) is not None:
            pass
        go, done = open_turns(cfg.get("turns"))
        rtt = []
        total, block = cfg["warmup"] + cfg["reps"], cfg.get("block", 0) or 1
        for count in range(total):
            if go is not None and count % block == 0:
                os.read(go, 1)
            settled = time.monotonic() + cfg.get("settle_s", 0.0)
            while time.monotonic() < settled:  # awake: the echo finishes its reply, this CPU stays warm
                pass
            start = send(count, payload)
            while True:
                got = recv(10.0)
                if got is None:
                    raise SystemExit(f"rospy: reply {count} lost")
                if got[2] == top | count:
                    break
            if measured(count, cfg["warmup"], cfg.get("block", 0)):
                rtt.append(time.monotonic_ns() - start)
            if done is not None and (count % block == block - 1 or count == total - 1):
                os.write(done, b"d")
            if cfg.get("gap_s"):
                time.sleep(cfg["gap_s"])
        send(STOP, b"")
        time.sleep(0.2)
        write_result(cfg["ping_out"], {"rtt_ns": rtt})
    else:
        one_way = {}
        while True:
            got = recv(120.0)
            if got is None:
                raise SystemExit("rospy: echo waited 120 s")
            arrival, stamp, seq, data = got
            sender, count = seq >> TAG_SHIFT, seq & COUNT
            if count == STOP:
                write_result(cfg["echo_out"], {"one_way_ns": one_way} if cfg.get("serve") else
                             {"one_way_ns": one_way.get("0", [])})
                if cfg.get("serve"):
                    continue
                break
            if count != PROBE and measured(count, cfg["warmup"], cfg.get("block", 0)):
                one_way.setdefault(str(sender), []).append(arrival - stamp)
            pubs[sender].publish(UInt8MultiArray(data=bytes(data)))
    os._exit(0)


if __name__ == "__main__":
    main()
