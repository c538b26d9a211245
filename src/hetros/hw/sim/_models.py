"""fpgaDDS's two execution models of a chain of hardware nodes, simulated cycle for cycle.

Dataflow: the nodes are chained over hardware topics on one fpga target, so the streams
overlap (the second node starts on the first beat the first one sends) and a message
crosses the CPU only on its way in and out. Sequential: each node sits behind a gateway of
its own (ReconROS without hardware topics), so every intermediate message goes out to the
CPU and back in, whole, before the next node starts. Both are measured on the target's own
design by co-simulation: the dataflow model is the target as planned, the sequential one
each hardware node built alone (``hardware_topics(only=...)``) and fed what the one before
it produced.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..._errors import HardwareError
from ...msg import TypeRegistry, array_fields
from ...plan import Plan
from ._cosim import TargetSimulation


@dataclass(frozen=True)
class ModelLatency:
    """One execution model's latency for one message: cycles from the first beat offered to the last
    output beat taken, and how many times the message (or what became of it) crossed the CPU."""

    model: str
    cycles: int
    clock_mhz: float
    cpu_copies: int
    stages: list[tuple[str, int]] = field(default_factory=list)

    @property
    def microseconds(self) -> float:
        return self.cycles / self.clock_mhz


_ENCODINGS = {1: "mono8", 3: "rgb8", 4: "rgba8"}


def sample_message(types: TypeRegistry, typename: str, image: tuple[int, int], size: int, seed: int = 0,
                   channels: int = 1) -> Any:
    """A message to time a chain with: an Image a random ``image`` (width, height) of ``channels`` bytes a
    pixel (mono8, rgb8: what the nodes that take it are built for); anything else with each
    variable-length primitive array ``size`` random elements long."""
    rng = np.random.default_rng(seed)
    cls = types.get(typename)
    if typename == "sensor_msgs/msg/Image":
        width, height = image
        if channels not in _ENCODINGS:
            raise HardwareError(f"an image sample must have 1, 3 or 4 bytes a pixel, not {channels!r}")
        return cls(width=width, height=height, encoding=_ENCODINGS[channels], step=width * channels,
                   data=rng.integers(0, 256, width * height * channels, dtype=np.uint8))
    message = cls()
    for array in array_fields(types, typename):
        if array.length is None and len(array.path) == 1:
            info = np.iinfo(array.dtype) if np.issubdtype(array.dtype, np.integer) else None
            values = (rng.integers(info.min, info.max, size, dtype=array.dtype, endpoint=True) if info is not None
                      else rng.random(size).astype(array.dtype))
            setattr(message, array.path[0], values)
    return message


def _encoded(types: TypeRegistry, typename: str, message: Any) -> bytes:
    codec = types.codec(typename)
    body = bytearray(codec.size(message))
    codec.encode(message, memoryview(body))
    return bytes(body)


def one_message_through(simulation: TargetSimulation, inputs: dict[str, bytes],
                        max_cycles: int) -> tuple[int, dict[str, bytes]]:
    """Push one message into each input port; the cycles until every output port ended one, and those."""
    top = simulation.top
    missing = [p.topic for p in simulation.inputs if p.topic not in inputs]
    if missing:
        raise HardwareError(f"no message to time {', '.join(missing)} with")
    for port in simulation.inputs:
        top.push(port.index, inputs[port.topic])
    start = top.cycle
    produced: dict[str, bytes] = {}
    while len(produced) < len(simulation.outputs):
        if top.cycle - start > max_cycles:
            waiting = [p.topic for p in simulation.outputs if p.topic not in produced]
            raise HardwareError(f"fpga target {simulation.target}: nothing on {', '.join(waiting)} after "
                                f"{max_cycles:,} cycles; does the chain drop the message?")
        top.run(max_cycles, 1)
        for port in simulation.outputs:
            body = top.pop(port.index)
            if body is not None and port.topic not in produced:
                produced[port.topic] = body
    return top.cycle - start, produced


def execution_models(plan: Plan, target: str, types: TypeRegistry, samples: dict[str, Any],
                     max_cycles: int = 100_000_000) -> list[ModelLatency]:
    """The dataflow and the sequential latency of ``target``'s hardware nodes for one message per input
    topic (``samples``: topic -> message)."""
    whole = TargetSimulation(plan, target, types)
    clock = whole.clock_mhz  # clock_mhz, or the Fmax place and route achieved where that is lower
    components = whole.components
    try:
        inputs = {p.topic: _encoded(types, p.type, samples[p.topic]) for p in whole.inputs if p.topic in samples}
        cycles, out_of_dataflow = one_message_through(whole, inputs, max_cycles)
        dataflow = ModelLatency("dataflow (hardware topics between the nodes)", cycles, clock,
                                len(whole.inputs) + len(whole.outputs))
    finally:
        whole.close()
    hardware = [n for n, spec in plan.nodes.items() if spec.target == target and plan.in_hardware(n)]
    available = dict(inputs)
    stages: list[tuple[str, int]] = []
    copies = 0
    while hardware:
        ready = next((n for n in hardware if all(t in available for t in plan.nodes[n].subscribe)), None)
        if ready is None:
            raise HardwareError(f"fpga target {target}: nodes {', '.join(hardware)} wait on topics nothing feeds "
                                "(a loop?); the sequential model needs a chain")
        hardware.remove(ready)
        alone = TargetSimulation(plan, target, types, only={ready})
        try:
            cycles, produced = one_message_through(alone, available, max_cycles)
            copies += len(alone.inputs) + len(alone.outputs)
        finally:
            alone.close()
        available.update(produced)
        stages.append((ready, cycles))
        _check_against_twins(plan, target, types, samples, components, produced, f"sequential stage {ready}")
    sequential = ModelLatency("sequential (each node behind its own gateway)", sum(c for _, c in stages), clock,
                              copies, stages)
    _check_against_twins(plan, target, types, samples, components, out_of_dataflow, "dataflow")
    return [dataflow, sequential]


def _twin_outputs(plan: Plan, target: str, samples: dict[str, Any], components: dict[str, Any]) -> dict[str, Any]:
    """What the target's nodes' software twins make of ``samples``, topic by topic, along the chain (a node
    without a twin, or with several inputs, leaves its outputs unknown)."""
    messages = dict(samples)
    pending = [n for n, spec in plan.nodes.items() if spec.target == target and plan.in_hardware(n)]
    while pending:
        ready = next((n for n in pending if all(t in messages for t in plan.nodes[n].subscribe)), None)
        if ready is None:
            break
        pending.remove(ready)
        spec = plan.nodes[ready]
        make = getattr(components.get(ready), "twin", None)
        twin = make() if make is not None else None
        if twin is None or len(spec.subscribe) != 1 or len(spec.publish) != 1:
            continue
        (topic_in,), (topic_out,) = spec.subscribe, spec.publish
        messages[topic_out] = twin(messages[topic_in])
    return messages


def _check_against_twins(plan: Plan, target: str, types: TypeRegistry, samples: dict[str, Any],
                         components: dict[str, Any], produced: dict[str, bytes], what: str) -> None:
    """Every output the hardware produced is its software twin's, bit for bit: a timing of a wrong result is
    no timing (HardwareError naming the topic and how many bytes differ)."""
    expected = _twin_outputs(plan, target, samples, components)
    for topic, body in produced.items():
        want = expected.get(topic)
        if want is None or topic in samples:
            continue
        typename = want.__msgtype__
        got = types.codec(typename).decode(memoryview(body))
        if not hasattr(want, "data"):
            continue
        have, need = np.asarray(got.data), np.asarray(want.data)
        if have.shape != need.shape or not np.array_equal(have, need):
            wrong = int(np.count_nonzero(have != need)) if have.shape == need.shape else max(have.size, need.size)
            raise HardwareError(f"fpga target {target}, {what}: the hardware's {topic} differs from its software "
                                f"twin in {wrong} of {need.size} bytes; the timing of a wrong result is no timing")


def format_models(target: str, rows: list[ModelLatency]) -> str:
    lines = [f"| fpga target {target} | cycles | at clock | CPU copies per message | stages |", "|---|---|---|---|---|"]
    for row in rows:
        stages = ", ".join(f"{name} {cycles:,}" for name, cycles in row.stages) or "overlapped"
        lines.append(f"| {row.model} | {row.cycles:,} | {row.microseconds:,.1f} µs at {row.clock_mhz:g} MHz | "
                     f"{row.cpu_copies} | {stages} |")
    if len(rows) == 2 and rows[0].cycles:
        lines += ["", f"Dataflow is {rows[1].cycles / rows[0].cycles:.2f}x faster than sequential, with "
                      f"{rows[1].cpu_copies - rows[0].cpu_copies} fewer CPU copies per message. The sequential "
                      "figure counts the hardware's cycles only: each of its extra copies adds the software "
                      "transfer time on top."]
    return "\n".join(lines)


def channels_of(plan: Plan, target: str, topic: str) -> int:
    """The bytes a pixel of the images on ``topic`` have, as the target's hardware nodes that take them are
    built (their ``channels`` parameter; 1 where none says)."""
    found = {int(spec.parameters.get("channels", 1)) for name, spec in plan.nodes.items()
             if spec.target == target and plan.in_hardware(name) and topic in spec.subscribe}
    if len(found) > 1:
        raise HardwareError(f"the hardware nodes that take {topic} are built for different pixels ({sorted(found)} "
                            "bytes): give them one channels parameter")
    return found.pop() if found else 1
