"""Timing is a check: nextpnr's critical path named, a missed clock an error, and the figures of a design
that misses its clock given at the Fmax it achieves (``hetros.hw.flow._bitstream``, ``hetros.hw.top._clock``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from hetros.hw.flow._bitstream import Bitstream, critical_path
from hetros.hw.top._clock import record_fmax, target_clock
from hetros.plan import Plan, TargetPlan

pytest.importorskip("amaranth")


def _segment(kind: str, start: str, end: str, delay: float, source: str = "") -> dict[str, object]:
    found: dict[str, object] = {"type": kind, "delay": delay, "from": {"cell": start, "port": "Q"},
                                "to": {"cell": end, "port": "D"}}
    if source:
        found["sources"] = [f"/venv/lib/python3.11/site-packages/{source}"]
    return found


# the shape of nextpnr-ecp5's --report JSON: two paths, the second the longer
REPORT = {
    "fmax": {"clk": {"achieved": 48.2, "constraint": 100}},
    "critical_paths": [
        {"from": "posedge clk", "to": "posedge clk", "path": [
            _segment("clk-to-q", "design.echo.r", "design.echo.r", 0.5),
            _segment("routing", "design.echo.r", "design.echo.q", 1.0, "amaranth/lib/fifo.py:279"),
            _segment("setup", "design.echo.q", "design.echo.q", 0.1)]},
        {"from": "posedge clk", "to": "posedge clk", "path": [
            _segment("clk-to-q", "design.sobel.line_older_FF", "design.sobel.line_older_FF", 0.5),
            _segment("routing", "design.sobel.line_older_FF", "design.sobel.sum_LUT4", 6.0, "hetros/hw/_image.py:120"),
            _segment("logic", "design.sobel.sum_LUT4", "design.sobel.sum_LUT4", 0.4),
            _segment("routing", "design.sobel.sum_LUT4", "design.sobel.out_LUT4", 3.0, "hetros/hw/_image.py:131"),
            _segment("logic", "design.sobel.out_LUT4", "design.sobel.out_LUT4", 0.4),
            _segment("routing", "design.sobel.out_LUT4", "design.sobel.out_FF", 10.0),
            _segment("setup", "design.sobel.out_FF", "design.sobel.out_FF", 0.45)]},
    ],
}


def test_the_longest_critical_path_is_named_with_its_node_and_source_lines() -> None:
    path = critical_path(REPORT)
    assert path is not None
    assert (path.start, path.end, path.part, path.levels) == ("design.sobel.line_older_FF", "design.sobel.out_FF",
                                                              "sobel", 2)
    assert path.logic_ns == pytest.approx(0.5 + 0.4 + 0.4 + 0.45)
    assert path.routing_ns == pytest.approx(19.0)
    assert path.describe() == ("sobel.line_older_FF -> sobel.out_FF: 20.8 ns over 2 logic levels (1.8 ns logic, "
                               "19.0 ns routing); from hetros/hw/_image.py:120, hetros/hw/_image.py:131")
    assert critical_path({"fmax": {}}) is None


def test_a_design_that_misses_its_clock_says_by_how_much_and_where() -> None:
    row = Bitstream("fpga", "LFE5U-25KF-CABGA381", Path("fpga.bit"), 48.2, 100.0, 900, 800, 3.0, critical_path(REPORT))
    assert not row.meets_clock
    assert row.timing_failure().startswith("fpga misses its clock: place and route achieved 48.2 MHz on "
                                           "LFE5U-25KF-CABGA381, clock_mhz is 100 MHz; its critical path, in sobel: "
                                           "sobel.line_older_FF -> sobel.out_FF")
    assert Bitstream("fpga", "x", Path("x.bit"), 100.0, 100.0, 1, 1, 1.0).meets_clock


def test_a_router_that_runs_out_of_time_is_named_and_the_table_says_which_routed(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """nextpnr's first router may not finish a congested design; the flow stops it at its time limit (a
    real process here), places the design again spread out and routes it with router2, and the table
    says so."""
    from hetros import HardwareError
    from hetros.hw.flow import _bitstream
    from hetros.hw.flow._bitstream import SPREAD, _run, format_bitstreams

    with pytest.raises(HardwareError, match=r"sleep ran past 0.2 s"):
        _run(["sleep", "5"], tmp_path, "sleep", timeout=0.2)
    # a stand-in for nextpnr (the flow is under test, not the tool): router1 never finishes, the rest is logged
    fake = tmp_path / "nextpnr"
    fake.write_text('#!/bin/sh\ncase "$*" in *router1*) exec sleep 30;; esac\necho "$*" >> calls.txt\n')
    fake.chmod(0o755)
    monkeypatch.setattr(_bitstream, "ROUTER1_SECONDS", 0.3)
    assert _bitstream._place_and_route(str(fake), "--85k", "CABGA756", 100.0, 1, tmp_path) == SPREAD
    (call,) = (tmp_path / "calls.txt").read_text().splitlines()
    assert call.endswith("--placer static --router router2") and "--freq 100" in call
    (tmp_path / "fpga.bit").write_bytes(b"x" * 2048)
    row = Bitstream("fpga", "LFE5U-25KF-CABGA381", tmp_path / "fpga.bit", 103.0, 100.0, 900, 800, 3.0,
                    router=SPREAD)
    assert "| 103.0 MHz, static placer, router2 | 100 MHz | fpga.bit (2 KiB) |" in format_bitstreams([row])


def test_figures_use_the_achieved_clock_where_it_is_below_clock_mhz(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    plan = Plan(name="p", root=str(tmp_path), message_paths=(), nodes={}, channels={}, edges=(),
                targets={"fpga": TargetPlan(name="fpga", kind="fpga", clock_mhz=100.0)})
    assert target_clock(plan, "fpga", "k1").mhz == 100.0
    assert "no `hetros hw bitstream` of this design yet" in target_clock(plan, "fpga", "k1").source
    record_fmax("k1", 48.2, "LFE5U-25KF-CABGA381", "a -> b")
    slow = target_clock(plan, "fpga", "k1")
    assert slow.mhz == 48.2 and slow.source.startswith("the Fmax place and route achieved on LFE5U-25KF-CABGA381")
    record_fmax("k2", 187.0, "LFE5U-25KF-CABGA381", "")
    fast = target_clock(plan, "fpga", "k2")
    assert fast.mhz == 100.0 and "which place and route met" in fast.source and "187.0 MHz" in fast.source
    (tmp_path / "hetros" / "fmax" / "k3.json").write_text("{not json")
    assert target_clock(plan, "fpga", "k3").mhz == 100.0  # a damaged record is no figure


def test_a_target_placed_node_by_node_is_bounded_by_its_slowest_node(tmp_path: Path,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """``--parts parts`` (or a target too big for any ECP5) records its slowest node alone as an upper bound,
    said as such, and never in place of a record of the whole target."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    plan = Plan(name="p", root=str(tmp_path), message_paths=(), nodes={}, channels={}, edges=(),
                targets={"fpga": TargetPlan(name="fpga", kind="fpga", clock_mhz=100.0)})
    record_fmax("k1", 91.5, "LFE5U-85KF-CABGA756", "node blur: a -> b", nodes_alone=True)
    bound = target_clock(plan, "fpga", "k1")
    assert bound.mhz == 91.5
    assert "its slowest node placed alone on LFE5U-85KF-CABGA756" in bound.source and "upper bound" in bound.source
    record_fmax("k1", 104.0, "LFE5U-85KF-CABGA756", "", nodes_alone=True)
    assert target_clock(plan, "fpga", "k1").mhz == 100.0 and "upper bound" in target_clock(plan, "fpga", "k1").source
    record_fmax("k1", 87.0, "LFE5U-85KF-CABGA756", "a -> b")
    record_fmax("k1", 99.0, "LFE5U-85KF-CABGA756", "node blur", nodes_alone=True)
    whole = target_clock(plan, "fpga", "k1")
    assert whole.mhz == 87.0 and "upper bound" not in whole.source


def test_a_design_too_big_for_the_device_is_named_by_the_cells_nextpnr_lacks() -> None:
    """nextpnr's utilisation table of the 512-bit lane-following target (Yosys counted 44,367 LUT4s, so the
    flow chose an LFE5U-85F; carry chains and lone flip-flops take the rest): only what overflows counts."""
    from hetros.hw.flow._bitstream import overfull

    log = ("Info: \t        ECLKBRIDGECS:       0/      2     0%\n"
           "Info: \t          TRELLIS_FF:   75721/  83640    90%\n"
           "Info: \t        TRELLIS_COMB:   85029/  83640   101%\n"
           "Info: \t        TRELLIS_RAMW:    1314/  10455    12%\n"
           "ERROR: Unable to find legal placement for all cells, design is probably at utilisation limit.\n")
    assert overfull(log) == [("TRELLIS_COMB", 85029, 83640)]
    assert overfull("Info: TRELLIS_FF: 10/ 20 50%") == []


def test_the_device_is_chosen_by_logic_cells_and_block_rams_not_lut4s_alone() -> None:
    """Yosys's stat of the 512-bit lane-following target and of its compensation alone: by LUT4s they
    would take an LFE5U-85F at 53 % and an LFE5U-45F; flip-flops and carry cells fill them, and the
    compensation's 128 block RAMs fit only the 85F's 208. A small design still takes the smallest part."""
    from hetros.hw.flow._bitstream import logic_cells, smallest_device

    target = ("   136305 cells\n    11972   CCU2C\n      128   DP16KD\n    44367   LUT4\n     2767   PFUMX\n"
              "     1314   TRELLIS_DPR16X4\n    75721   TRELLIS_FF\n")
    assert logic_cells(target) == 75721
    assert smallest_device(target) == 2
    compensation = "     5000   CCU2C\n      128   DP16KD\n    30000   LUT4\n    20000   TRELLIS_FF\n"
    assert logic_cells(compensation) == 40000 and smallest_device(compensation) == 2
    small = "      120   CCU2C\n        4   DP16KD\n     2400   LUT4\n     2200   TRELLIS_FF\n"
    assert logic_cells(small) == 2640 and smallest_device(small) == 0


def test_placing_a_target_builds_its_hardware_nodes_only_for_the_design(tmp_path: Path,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """Components made and never elaborated make Amaranth warn, which `hw bitstream` printed twice."""
    import gc
    import warnings

    from hetros.hw.flow import _bitstream
    from hetros.msg import registry
    from hetros.project import load_project, plan

    class Placed(Exception):
        pass

    def place(*_args: object, **_kwargs: object) -> None:
        raise Placed

    monkeypatch.setattr(_bitstream, "build_bitstream", place)  # what comes before place and route is under test
    planned = plan(load_project(Path(__file__).resolve().parents[2] / "examples" / "lane_following" /
                                "project_fpga.yaml"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(Placed):
            _bitstream.bitstreams(planned, "fpga", tmp_path, registry(), "target")
        gc.collect()
    assert [w.category.__name__ for w in caught] == []


def test_the_fmax_is_recorded_for_the_design_as_it_was_when_placing_began(tmp_path: Path,
                                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """Placing the 512-bit compensation took 45 minutes, and a design file edited meanwhile gave the figure
    to the edited design: the key is taken before anything is built."""
    from hetros.hw.flow import _bitstream
    from hetros.hw.top import _clock
    from hetros.msg import registry
    from hetros.project import load_project, plan

    keys = iter(["as placed", "as edited meanwhile"])
    recorded: list[str] = []
    monkeypatch.setattr(_clock, "target_key", lambda *_args: next(keys))
    monkeypatch.setattr(_clock, "record_fmax", lambda key, *_args, **_kwargs: recorded.append(key))
    monkeypatch.setattr(_bitstream, "build_bitstream", lambda *_args, **_kwargs: Bitstream(
        "target", "LFE5U-25KF-CABGA381", tmp_path / "fpga.bit", 90.0, 100.0, 1, 1, 1.0))
    planned = plan(load_project(Path(__file__).resolve().parents[2] / "examples" / "lane_following" /
                                "project_fpga.yaml"))
    _bitstream.bitstreams(planned, "fpga", tmp_path, registry(), "target")
    assert recorded == ["as placed"]


def test_a_designs_key_is_the_same_whether_or_not_its_nodes_module_was_imported() -> None:
    """`hetros hw bitstream` imports the nodes' module before it records the Fmax; a benchmark that only reads
    the clock may not have, and then found no figure for the same design."""
    import subprocess
    import sys

    script = ("import sys\nfrom hetros.project import plan_file\nfrom hetros.hw.top._clock import target_key\n"
              "if sys.argv[1] == 'imported':\n    import hetros.hw.nodes\n"
              "print(target_key(plan_file('examples/lane_following/project_fpga.yaml'), 'fpga'))\n")
    root = Path(__file__).resolve().parents[2]
    keys = {subprocess.run([sys.executable, "-c", script, how], cwd=root, capture_output=True, text=True,
                           check=True).stdout for how in ("imported", "not imported")}
    assert len(keys) == 1 and len(keys.pop().strip()) == 64


@pytest.mark.parametrize("outputs", [1, 4, 5, 75, 577])
def test_the_pin_harness_folds_every_output_four_bits_a_stage(outputs: int) -> None:
    """The harness must never be a design's critical path: each registered XOR reads at most four bits, and
    the folds still give the parity of every output (so none is optimised away)."""
    import random
    import re

    from hetros.hw.flow._bitstream import pin_harness

    design = f"module d (input wire clk, input wire rst, input wire a, output wire [{outputs - 1}:0] y);\nendmodule\n"
    design = design.replace("(input", "(\n  input").replace(", ", ",\n  ")
    harness = pin_harness(design, "d")
    assert f"reg [{outputs - 1}:0] held;" in harness, harness
    held = [random.getrandbits(1) for _ in range(outputs)]
    values = {"held": held}
    for name, bit, source, high, low in re.findall(r"(\w+)\[(\d+)\] <= \^(\w+)\[(\d+):(\d+)\];", harness):
        assert int(high) - int(low) < 4
        values.setdefault(name, []).append(sum(values[source][int(low):int(high) + 1]) % 2)
        assert len(values[name]) == int(bit) + 1
    (last,) = re.findall(r"sout <= \^(\w+);", harness)
    assert len(values[last]) <= 4
    assert sum(values[last]) % 2 == sum(held) % 2


def test_a_clock_faster_than_an_ecp5_can_give_is_capped_and_said_so(tmp_path: Path) -> None:
    """A topic network alone routes at 507 MHz in nextpnr's timing model; no clock of the part reaches that."""
    from hetros import HardwareError
    from hetros.hw.flow._bitstream import ECP5_CLOCK_LIMIT_MHZ, achieved_clock, format_bitstreams

    report = {"fmax": {"clk": {"achieved": 507.2, "constraint": 100.0}, "other": {"achieved": 612.0}}}
    assert achieved_clock(report, "net") == (ECP5_CLOCK_LIMIT_MHZ, 507.2)
    assert achieved_clock({"fmax": {"clk": {"achieved": 96.7}}}, "fpga") == (96.7, 0.0)
    with pytest.raises(HardwareError, match="nextpnr reported no clock for net"):
        achieved_clock({}, "net")
    (tmp_path / "net.bit").write_bytes(b"x" * 1024)
    row = Bitstream("net", "LFE5U-25KF-CABGA381", tmp_path / "net.bit", 400.0, 100.0, 90, 80, 1.0, routed_mhz=507.2)
    assert "| 400.0 MHz (capped: routed at 507.2 MHz, but an ECP5's PLLs give at most 400 MHz) | 100 MHz |" in \
        format_bitstreams([row])
