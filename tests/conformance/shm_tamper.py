"""Run as a script by test_shm_specific: a same-user process rewrites a sample's size (iceoryx2's
``number_of_elements``) and its array length in shared memory after it was sent. The reader
must drop it and go on, not die of SIGSEGV. Prints the outcome as one line of JSON."""

from __future__ import annotations

import ctypes
import json
import struct
import sys

import numpy as np

from hetros.msg import registry
from hetros.transport import MessageCodec, QoS, ShmDomain, new_session, remove_session_segments
from hetros.transport.shm._sample import HEADER, LAYOUT_CDR

TYPE = "sensor_msgs/msg/Image"


def main() -> None:
    huge_size, huge_count = int(sys.argv[1]), int(sys.argv[2])
    session = new_session()
    codec = MessageCodec(registry(), TYPE)
    Image = registry().get(TYPE)
    publishing, subscribing = ShmDomain(session, "pub"), ShmDomain(session, "sub")
    try:
        reader = subscribing.open_reader("/img", ["pub"], QoS(depth=4), codec, 0, lambda: None, "sub")
        writer = publishing.open_writer("/img", "pub", QoS(depth=4), codec)
        service = writer._service
        body = bytearray(codec.size(Image(width=1, data=np.zeros(16, np.uint8))))
        codec.encode_into(Image(width=1, data=np.zeros(16, np.uint8)), memoryview(body))
        sample, memory = service.loan(HEADER.size + len(body))
        address = sample.payload_ptr
        memory[HEADER.size:] = body
        service.send(sample, memory, LAYOUT_CDR, 0)
        # after the send, as another process of the same user could: the array's length and the size
        struct.pack_into("<I", memory, HEADER.size + len(body) - 20, huge_count)
        ctypes.c_uint64.from_address(address - 16).value = huge_size
        del sample, memory
        taken = reader.try_take()
        total = int(taken.data.astype(np.uint64).sum()) if taken is not None else None  # reads every byte
        writer.write(Image(width=2, data=np.full(16, 3, np.uint8)))
        after = reader.try_take()
        print(json.dumps({"first": None if taken is None else int(taken.width), "sum": total,
                          "after": int(after.width), "dropped": reader.dropped}))
        reader.close()
    finally:
        publishing.close()
        subscribing.close()
        remove_session_segments(session)


if __name__ == "__main__":
    main()
