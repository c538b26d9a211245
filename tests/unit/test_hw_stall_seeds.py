"""Every fpga example's hardware under seeded random stalls, as a verification team drives a design: each
gateway input rests between beats and each output is not ready on a quarter of the cycles, under eight seeds.
A node that relies on TREADY staying high, or on TVALID arriving back to back, gives other bytes (or breaks
the port checker's AXI4-Stream rules); a well-made one gives the bytes of the unstalled run, which are its
software twins' (checked where the node has a twin)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

pytest.importorskip("amaranth")

from hetros.hw import TargetSimulation, channels_of, one_message_through, sample_message
from hetros.hw.sim._models import _check_against_twins, _encoded
from hetros.msg import TypeRegistry, registry
from hetros.project import load_project, plan

pytestmark = [pytest.mark.rtl, pytest.mark.timeout(900),
              pytest.mark.skipif(shutil.which("verilator") is None, reason="Debian's verilator is not installed")]

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SEEDS = range(1, 9)
# the examples whose hardware nodes take topics from software (a service's requests and hardware TCPROS frames go
# through tests of their own; hw_topics is a topic network whose nodes are all software stand-ins)
PROJECTS = ["sobel_hw/project_fpga.yaml", "sobel_hw/project_chain_fpga.yaml", "lane_following/project_fpga.yaml",
            "ping_pong/project_fpga.yaml", "ping_pong/project_fpga_verilog.yaml", "sorting/project_fpga.yaml"]


def _types(folders: tuple[str, ...]) -> TypeRegistry:
    types = registry()
    for folder in folders:
        types.load_folder(Path(folder))
    return types


@pytest.mark.parametrize("project", PROJECTS)
def test_every_example_gives_its_bytes_under_eight_stall_seeds(project: str) -> None:
    made = plan(load_project(EXAMPLES / project))
    types = _types(made.message_paths)
    for target in (name for name, spec in made.targets.items() if spec.kind == "fpga"):
        calm = TargetSimulation(made, target, types)
        try:
            samples = {p.topic: sample_message(types, p.type, (64, 48), 40, channels=channels_of(made, target, p.topic))
                       for p in calm.inputs}
            inputs = {p.topic: _encoded(types, p.type, samples[p.topic]) for p in calm.inputs}
            unstalled_cycles, expected = one_message_through(calm, inputs, 50_000_000)
            _check_against_twins(made, target, types, samples, calm.components, expected, "unstalled")
        finally:
            calm.close()
        slowest = 0
        for seed in SEEDS:
            stalled = TargetSimulation(made, target, types)
            try:
                assert isinstance(stalled.top, type(calm.top))
                stalled.top.stalls(seed, 25.0)  # type: ignore[union-attr]
                cycles, produced = one_message_through(stalled, inputs, 50_000_000)
            finally:
                stalled.close()
            assert produced == expected, f"{project} target {target}: seed {seed} changed the output bytes"
            slowest = max(slowest, cycles)
        assert slowest > unstalled_cycles, f"{project} target {target}: no seed slowed its ports"
