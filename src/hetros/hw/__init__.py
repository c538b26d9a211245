"""Hardware: fpga targets' topic networks as Amaranth components, their beats, Verilog and reports.

A topic whose publishers and subscribers all sit on one fpga target is a hardware topic
(fpgaDDS): an AXI-Stream network of wiring, a round-robin arbiter, a broadcast and FIFOs,
generated from the plan. Amaranth is imported only when a network is built.
"""

from pathlib import Path

from ..msg import TypeRegistry
from ..plan import Plan
from ._beats import BeatCodec, Beats, amaranth_layout, field_name, from_beats, to_beats


def build_target(plan: Plan, target: str, out: Path, types: TypeRegistry) -> tuple[Path, Path]:
    """Write the Verilog top and JSON manifest of ``target``'s topic network into ``out``."""
    from ._build import build

    return build(plan, target, out, types)


__all__ = ["BeatCodec", "Beats", "amaranth_layout", "build_target", "field_name", "from_beats",
           "to_beats"]
