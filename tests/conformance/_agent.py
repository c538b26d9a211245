"""A subscriber in another process, driven over stdin/stdout with JSON lines (test helper).

Commands: {"op": "open", ...}, {"op": "take"}, {"op": "pending"}, {"op": "close"}. Replies are
{"reply": ...}; wake-ups of the reader arrive as {"event": "wake"} at any time.
Message data travels back through a file in the directory named by the first argument, so 64 MiB
payloads stay cheap.
"""

from __future__ import annotations

import json
import sys
import threading
from pathlib import Path
from typing import Any

from hetros.msg import registry
from hetros.transport import MessageCodec, QoS, ShmDomain, WakeChannel

_out_lock = threading.Lock()


def send(obj: dict[str, Any]) -> None:
    with _out_lock:
        sys.stdout.write(json.dumps(obj) + "\n")
        sys.stdout.flush()


def pump(channel: WakeChannel) -> None:
    """Stands in for the owner node's executor: waits on its wake channel, runs the wakes."""
    while True:
        channel.wait(0.05)


def main() -> None:
    domain: ShmDomain | None = None
    reader: Any = None
    spool = Path(sys.argv[1])  # the test owns it, and removes it however this process ends
    count = 0
    for line in sys.stdin:
        cmd = json.loads(line)
        op = cmd["op"]
        if op == "open":
            domain = ShmDomain(cmd["session"], cmd["name"])
            codec = MessageCodec(registry(), cmd["type"])
            reader = domain.open_reader(cmd["topic"], cmd["targets"], QoS(**cmd["qos"]), codec,
                                        cmd["slot"], lambda: send({"event": "wake"}), cmd["name"])
            threading.Thread(target=pump, args=(domain.wake_channel(cmd["name"]),), daemon=True).start()
            send({"reply": "opened"})
        elif op == "take":
            message = reader.try_take()
            if message is None:
                send({"reply": None})
                continue
            count += 1
            path = spool / f"{count}.bin"
            message.data.tofile(path)
            send({"reply": {"height": int(message.height), "width": int(message.width),
                            "file": str(path), "readonly": not message.data.flags.writeable,
                            "frozen": message.is_frozen}})
        elif op == "pending":
            send({"reply": reader.pending()})
        elif op == "counters":
            send({"reply": reader.counters()})
        elif op == "close":
            reader.close()
            assert domain is not None
            domain.close()
            send({"reply": "closed"})
            return


if __name__ == "__main__":
    main()
