"""Coverage-guided fuzzing of the C code that parses untrusted bytes, under AddressSanitizer and UBSan.

The compiled CDR and ROS 1 codec (``src/hetros/msg/_ccdr.c``) decodes every message that arrives from a
socket or from shared memory another process of the user can write; the slot reader
(``src/hetros/transport/shm/_cslot.c``) takes samples out of shared memory. This script builds both with
clang's ``-fsanitize=fuzzer-no-link,address,undefined`` into ``out/fuzz/``, loads them in place of the
normal build, and runs libFuzzer (through atheris) on one target:

- ``cdr``: bytes decoded as each of a set of message types (strings, sequences, fixed arrays, nested
  messages, images, point clouds, transforms), on the compiled path; a decode must return a message or
  raise hetros's SerializationError, and never touch memory it does not own;
- ``ros1``: the same bytes through the ROS 1 codec;
- ``slot``: bytes written into a shared-memory sample between a publisher and a subscriber of one
  process, taken by the compiled reader (``take_cdr``): the sample is taken or dropped, counted.

The corpus is kept in ``fuzz/corpus/<target>/`` (seeded from well-formed messages); what a run adds that
reaches new code goes to ``out/fuzz/corpus/<target>/`` (fold it in with libFuzzer's ``-merge=1``). Run it
with the sanitizer runtime preloaded, as ``make fuzz`` does::

    make fuzz                      # every target, 1,000,000 executions each (the long run)
    make fuzz FUZZ_RUNS=20000      # a short run (make test runs 20,000 per target)

Findings are written as ``out/fuzz/crash-*`` (libFuzzer's own files) and fail the run.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import subprocess
import sys
import sysconfig
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "fuzz"
CORPUS = ROOT / "fuzz" / "corpus"
SOURCES = {"hetros.msg._ccdr": ROOT / "src" / "hetros" / "msg" / "_ccdr.c",
           "hetros.transport.shm._cslot": ROOT / "src" / "hetros" / "transport" / "shm" / "_cslot.c"}
FLAGS = ["-O1", "-g", "-fno-omit-frame-pointer", "-fsanitize=fuzzer-no-link,address,undefined",
         "-fno-sanitize-recover=undefined", "-std=c11", "-shared", "-fPIC"]
TYPES = ["std_msgs/msg/String", "std_msgs/msg/Header", "sensor_msgs/msg/Image", "sensor_msgs/msg/PointCloud2",
         "tf2_msgs/msg/TFMessage", "sensor_msgs/msg/JointState", "visualization_msgs/msg/MarkerArray",
         "std_msgs/msg/Float64MultiArray", "diagnostic_msgs/msg/DiagnosticArray", "nav_msgs/msg/Path"]


def build() -> dict[str, Path]:
    """Both extensions, instrumented, under ``out/fuzz`` (rebuilt when their source is newer)."""
    OUT.mkdir(parents=True, exist_ok=True)
    include = sysconfig.get_paths()["include"]
    numpy_include = __import__("numpy").get_include()
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    built = {}
    for module, source in SOURCES.items():
        target = OUT / f"{module.rsplit('.', 1)[1]}{suffix}"
        if not target.exists() or target.stat().st_mtime < source.stat().st_mtime:
            subprocess.run([os.environ.get("FUZZ_CC", "clang-14"), *FLAGS, f"-I{include}", f"-I{numpy_include}",
                            str(source), "-o", str(target)], check=True)
        built[module] = target
    return built


def load_instrumented(built: dict[str, Path]) -> None:
    """The instrumented builds, registered under the extensions' own names before hetros imports them."""
    for module, path in built.items():
        spec = importlib.util.spec_from_file_location(module, path)
        assert spec is not None and spec.loader is not None
        loaded = importlib.util.module_from_spec(spec)
        sys.modules[module] = loaded
        spec.loader.exec_module(loaded)


def cdr_target(ros1: bool) -> Any:
    from hetros import Error
    from hetros.msg import registry
    from hetros.transport import MessageCodec

    types = registry()
    decoders = []
    for name in TYPES:
        if ros1:
            codec = types.ros1_codec(name)
            if codec is not None:
                decoders.append(lambda buffer, codec=codec: codec.decode(buffer[4:], 0, len(buffer) - 4))
        else:
            whole = MessageCodec(types, name)
            decoders.append(lambda buffer, whole=whole: whole.decode_at(buffer, 4, len(buffer)))

    def one(data: bytes) -> None:
        if not data:
            return
        decode = decoders[data[0] % len(decoders)]
        buffer = memoryview(bytes(4) + data[1:])  # the message at offset 4: its body 8-byte aligned
        try:
            decode(buffer)
        except Error:
            pass
    return one


def slot_target() -> Any:
    """A writer and a reader of one shared-memory topic in this process: each input's first bytes become the
    sample's header (sequence number, publisher slot, layout, time) and the rest its body, written into a
    loaned slot and sent; the compiled reader takes it (or drops it, counted)."""
    import atexit

    from hetros import Error
    from hetros.msg import registry
    from hetros.transport import MessageCodec, QoS, ShmDomain, new_session, remove_session_segments
    from hetros.transport.shm._sample import HEADER

    session = new_session()
    codec = MessageCodec(registry(), "sensor_msgs/msg/Image")
    publishing, subscribing = ShmDomain(session, "pub"), ShmDomain(session, "sub")
    reader = subscribing.open_reader("/img", ["pub"], QoS(depth=4, history="keep_last"), codec, 0, lambda: None,
                                     "sub")
    writer = publishing.open_writer("/img", "pub", QoS(depth=4, history="keep_last"), codec)
    service = writer._service

    def finish() -> None:
        reader.close()
        publishing.close()
        subscribing.close()
        remove_session_segments(session)
    atexit.register(finish)

    def one(data: bytes) -> None:
        if len(data) < 2:
            return
        layout = data[0] & 1
        body = data[1:]
        sample, memory = service.loan(HEADER.size + len(body))
        HEADER.pack_into(memory, 0, service.next_seq, 0, layout, 0)
        memory[HEADER.size:] = body
        service.send(sample, memory, layout, 0)
        del sample, memory
        try:
            while reader.try_take() is not None:
                pass
        except Error:
            pass
    return one


def main(argv: list[str]) -> int:
    import atheris

    target = argv[1] if len(argv) > 1 else "cdr"
    load_instrumented(build())
    one = {"cdr": lambda: cdr_target(False), "ros1": lambda: cdr_target(True), "slot": slot_target}[target]()
    kept = CORPUS / target  # in the repository: read, never written by a run
    found = OUT / "corpus" / target  # what this run adds (libFuzzer writes into the first folder)
    found.mkdir(parents=True, exist_ok=True)
    atheris.Setup([argv[0], str(found), str(kept), f"-artifact_prefix={OUT}/crash-{target}-", *argv[2:]], one)
    atheris.Fuzz()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
