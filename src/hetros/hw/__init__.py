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
from .streams._beats import BeatCodec, Beats, amaranth_layout, field_name, from_beats, to_beats


def build_target(plan: Plan, target: str, out: Path, types: TypeRegistry) -> tuple[Path, Path]:
    """Write the Verilog top and JSON manifest of ``target``'s topic network into ``out``."""
    from .top._build import build

    return build(plan, target, out, types)

if TYPE_CHECKING:
    from .flow._bitstream import available, bitstreams, build_bitstream, format_bitstreams
    from .flow._export import export
    from .sim._cosim import GatewayPort, SimulatedTop, TargetSimulation
    from .sim._models import channels_of, execution_models, format_models, one_message_through, sample_message
    from .sim._report import (
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
    from .sim._rtl import topic_verilog
    from .sim._sim import simulate
    from .sim._verilator import (
        DEFAULT_TRACE_WINDOW,
        IDLE,
        SIMULATOR_NICE_VARIABLE,
        STALLS_VARIABLE,
        TRACE_VARIABLE,
        TraceSetting,
        VerilatedTop,
        stall_setting,
    )
    from .top._build import hardware_topics, top_name
    from .top._clock import TargetClock, target_clock


# shared with other packages, loaded on first use (a worker must not pay for what it does not run)
_LAZY = {
    "DEFAULT_TRACE_WINDOW": ".sim._verilator",
    "GatewayPort": ".sim._cosim",
    "IDLE": ".sim._verilator",
    "Resources": ".sim._report",
    "SIMULATOR_NICE_VARIABLE": ".sim._verilator",
    "STALLS_VARIABLE": ".sim._verilator",
    "SimulatedTop": ".sim._cosim",
    "TABLE_I_PAPER_MS": ".sim._report",
    "TABLE_I_SIZES": ".sim._report",
    "TRACE_VARIABLE": ".sim._verilator",
    "TargetClock": ".top._clock",
    "TargetSimulation": ".sim._cosim",
    "TraceSetting": ".sim._verilator",
    "VerilatedTop": ".sim._verilator",
    "available": ".flow._bitstream",
    "bitstreams": ".flow._bitstream",
    "build_bitstream": ".flow._bitstream",
    "channels_of": ".sim._models",
    "execution_models": ".sim._models",
    "export": ".flow._export",
    "format_bitstreams": ".flow._bitstream",
    "format_models": ".sim._models",
    "format_resources": ".sim._report",
    "format_synth": ".sim._report",
    "format_transfers": ".sim._report",
    "hardware_topics": ".top._build",
    "part_of": ".sim._report",
    "one_message_through": ".sim._models",
    "sample_message": ".sim._models",
    "simulate": ".sim._sim",
    "stall_setting": ".sim._verilator",
    "synth_report": ".sim._report",
    "synthesize": ".sim._report",
    "synthesize_node": ".sim._report",
    "target_clock": ".top._clock",
    "top_name": ".top._build",
    "topic_verilog": ".sim._rtl",
    "transfer_cycles": ".sim._report",
    "transfer_report": ".sim._report",
}


__getattr__ = lazy_exports(__name__, _LAZY)


__all__ = [
    "DEFAULT_TRACE_WINDOW",
    "IDLE",
    "SIMULATOR_NICE_VARIABLE",
    "STALLS_VARIABLE",
    "TABLE_I_PAPER_MS",
    "TABLE_I_SIZES",
    "TRACE_VARIABLE",
    "BeatCodec",
    "Beats",
    "GatewayPort",
    "Resources",
    "SimulatedTop",
    "TargetClock",
    "TargetSimulation",
    "TraceSetting",
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
    "stall_setting",
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
