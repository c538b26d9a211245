"""The hardware side of a profile: each node with a ``hw:`` implementation, co-simulated alone on a
message its input carried while the project ran, at the clock its target achieves, with its
resources as Yosys counts them; and the fpga part's budget."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from .._errors import AdviseError, HardwareError
from ..plan import Plan
from ._model import Placement
from ._profile import Profile

if TYPE_CHECKING:
    from ..msg import TypeRegistry
    from ._observe import Observation

MAX_CYCLES = 200_000_000


def hardware_nodes(plan: Plan) -> list[str]:
    """The nodes that have a hardware implementation."""
    return sorted(n for n, spec in plan.nodes.items() if spec.hw)


def fpga_target(plan: Plan) -> str:
    """The project's fpga target (the first by name); "" when it has none."""
    return next((t for t, spec in sorted(plan.targets.items()) if spec.kind == "fpga"), "")


def part_budget(plan: Plan, target: str) -> dict[str, int]:
    """The fpga target's part as a budget per resource; AdviseError when the part is not one hetros knows."""
    from ..hw import part_of

    part = part_of(plan.targets[target].part)
    if part is None:
        raise AdviseError(f"fpga target {target}: part {plan.targets[target].part!r} is not one whose resources hetros "
                          "knows (hetros hw synth lists them); give the target a known part: for the advice's budget")
    return {"lut": part.luts, "ff": part.ffs, "bram": part.bram36, "dsp": part.dsps}


def hardware_profile(plan: Plan, project: Path, profile: Profile, observation: Observation) -> None:
    """Add to ``profile`` each hardware-capable node's time per message in hardware (``ms``, with the clock
    and where it came from) and resources, co-simulated on the first input its topic carried."""
    nodes = [n for n in hardware_nodes(plan) if n in profile.nodes]
    target = fpga_target(plan)
    if not nodes or not target:
        return
    from ..hw import TargetSimulation, one_message_through, part_of, synthesize_node
    from ..msg import registry

    variant, remove = _all_in_hardware(plan, project, nodes, target)
    try:
        types = registry()
        for folder in variant.message_paths:
            types.load_folder(Path(folder))
        part = part_of(variant.targets[target].part)
        for node in nodes:
            inputs = {}
            for topic in variant.nodes[node].subscribe:
                sample = observation.samples.get(topic)
                if sample is None:
                    raise AdviseError(f"node {node}: no message on {topic} while profiling, so its hardware cannot "
                                      "be timed on real input; run longer (--duration)")
                inputs[topic] = _body(types, variant.channels[topic].type, sample)
            alone = TargetSimulation(variant, target, types, only={node})
            try:
                cycles, _ = one_message_through(alone, inputs, MAX_CYCLES)
                component = alone.components[node]
                clock, source = alone.clock_mhz, alone.clock.source
            finally:
                alone.close()
            used = synthesize_node(component, part.family if part is not None else "xcup")
            profile.nodes[node].hardware = {
                "ms": cycles / clock / 1000.0, "cycles": cycles, "clock_mhz": clock, "clock": source,
                "target": target, "resources": {"lut": used.luts, "ff": used.ffs, "bram": used.bram36,
                                                "dsp": used.dsps}}
    except HardwareError as exc:
        raise AdviseError(f"co-simulating the hardware nodes for the profile failed: {exc}") from None
    finally:
        remove()


def _body(types: TypeRegistry, typename: str, sample: bytes) -> bytes:
    """The CDR body a hardware port takes (no encapsulation header, no padding after it) of a message
    as a tap gives it (the wire's bytes: encapsulation first). Fed the wire's bytes, a filter reads the
    encapsulation as the header's stamp and the image that follows at the wrong offsets."""
    from ..transport import MessageCodec

    codec = types.codec(typename)
    message = MessageCodec(types, typename).decode(memoryview(sample))
    body = bytearray(codec.size(message))
    codec.encode(message, memoryview(body))
    return bytes(body)


def _all_in_hardware(plan: Plan, project: Path, nodes: list[str], target: str) -> tuple[Plan, Callable[[], None]]:
    """``plan`` with every hardware-capable node on the fpga target (planned from a sibling file of the
    project, so that its relative paths hold), and how to remove that file."""
    from ..project import plan_file
    from ._report import write_project

    if all(plan.nodes[n].target == target for n in nodes):
        return plan, lambda: None
    from ._advise import mapping_of

    original, targets = mapping_of(plan)
    mapping = {n: Placement(target, (), fpga=True) if n in nodes else p for n, p in original.items()}
    handle = tempfile.NamedTemporaryFile(prefix=".advise-hw-", suffix=".yaml", dir=project.parent, delete=False)
    handle.close()
    path = Path(handle.name)
    write_project(project, mapping, original, targets, path)
    try:
        return plan_file(path), lambda: path.unlink(missing_ok=True)
    except Exception:
        path.unlink(missing_ok=True)
        raise
