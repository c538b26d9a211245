"""Hardware: fpga targets' topic networks as Amaranth components, their beats, Verilog and reports.

A topic whose publishers and subscribers all sit on one fpga target is a hardware topic
(fpgaDDS): an AXI-Stream network of wiring, a round-robin arbiter, a broadcast and FIFOs,
generated from the plan. Amaranth is imported only when a network is built.
"""

from pathlib import Path
from typing import TYPE_CHECKING

from .._lazy import lazy_exports
from ..msg import TypeRegistry
from ..plan import Plan
from ._beats import BeatCodec, Beats, amaranth_layout, field_name, from_beats, to_beats


def build_target(plan: Plan, target: str, out: Path, types: TypeRegistry) -> tuple[Path, Path]:
    """Write the Verilog top and JSON manifest of ``target``'s topic network into ``out``."""
    from ._build import build

    return build(plan, target, out, types)

if TYPE_CHECKING:
    from ._bitstream import available, bitstreams, build_bitstream, format_bitstreams
    from ._build import hardware_topics, top_name
    from ._clock import TargetClock, target_clock
    from ._cosim import GatewayPort, SimulatedTop, TargetSimulation
    from ._export import export
    from ._models import channels_of, execution_models, format_models, one_message_through, sample_message
    from ._report import (
        TABLE_I_PAPER_MS,
        TABLE_I_SIZES,
        Resources,
        format_resources,
        format_synth,
        format_transfers,
        part_of,
        synth_report,
        synthesize,
        synthesize_node,
        transfer_cycles,
        transfer_report,
    )
    from ._rtl import topic_verilog
    from ._sim import simulate
    from ._verilator import IDLE, VerilatedTop


# shared with other packages, loaded on first use (a worker must not pay for what it does not run)
_LAZY = {
    "GatewayPort": "._cosim",
    "IDLE": "._verilator",
    "Resources": "._report",
    "SimulatedTop": "._cosim",
    "TABLE_I_PAPER_MS": "._report",
    "TABLE_I_SIZES": "._report",
    "TargetClock": "._clock",
    "TargetSimulation": "._cosim",
    "VerilatedTop": "._verilator",
    "available": "._bitstream",
    "bitstreams": "._bitstream",
    "build_bitstream": "._bitstream",
    "channels_of": "._models",
    "execution_models": "._models",
    "export": "._export",
    "format_bitstreams": "._bitstream",
    "format_models": "._models",
    "format_resources": "._report",
    "format_synth": "._report",
    "format_transfers": "._report",
    "hardware_topics": "._build",
    "part_of": "._report",
    "one_message_through": "._models",
    "sample_message": "._models",
    "simulate": "._sim",
    "synth_report": "._report",
    "synthesize": "._report",
    "synthesize_node": "._report",
    "target_clock": "._clock",
    "top_name": "._build",
    "topic_verilog": "._rtl",
    "transfer_cycles": "._report",
    "transfer_report": "._report",
}


__getattr__ = lazy_exports(__name__, _LAZY)


__all__ = [
    "IDLE",
    "TABLE_I_PAPER_MS",
    "TABLE_I_SIZES",
    "BeatCodec",
    "Beats",
    "GatewayPort",
    "Resources",
    "SimulatedTop",
    "TargetClock",
    "TargetSimulation",
    "VerilatedTop",
    "amaranth_layout",
    "available",
    "bitstreams",
    "build_bitstream",
    "build_target",
    "channels_of",
    "execution_models",
    "export",
    "field_name",
    "format_bitstreams",
    "format_models",
    "format_resources",
    "format_synth",
    "format_transfers",
    "from_beats",
    "hardware_topics",
    "one_message_through",
    "part_of",
    "sample_message",
    "simulate",
    "synth_report",
    "synthesize",
    "synthesize_node",
    "target_clock",
    "to_beats",
    "top_name",
    "topic_verilog",
    "transfer_cycles",
    "transfer_report",
]
