"""Hardware topics against fpgaDDS's tables: transfer time per message size, resources per topic network.

    python benchmarks/hw.py [--quick] [--out DIR]      (or: hetros bench hw)

First it runs the ``rtl`` tests (the exported Verilog replays the Amaranth scoreboard under
Icarus with the same cycle counts; Yosys estimates). Then Table I's shape: one message of
each size through a 1-to-1 topic at 64 bits and 100 MHz, simulated (Icarus; Amaranth's
simulator beside it up to 12 kB, which must agree), next to the paper's fpgaDDS and
CycloneDDS times. Then Table II's shape: Yosys ``synth_xilinx -family xcup`` LUT/FF/BRAM/
LUTRAM per topic network (1x1, 2x3, 4x4, without and with 512-beat FIFOs). The paper's
Table II is the whole vehicle design, HLS nodes included: printed as context only.
Writes hw.md, hw.json and hw.png.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

from ..hw._report import TABLE_I_PAPER_MS, TABLE_I_SIZES, Resources, format_resources, synthesize, transfer_cycles
from ._provenance import provenance

# fpgaDDS Table I, CycloneDDS column (ms), and Table II (whole design on the XCZU7EV), for context
PAPER_CYCLONE_MS = {"3 kB": 0.06, "12 kB": 0.07, "50 kB": 0.19, "196 kB": 0.63, "786 kB": 2.34, "3146 kB": 9.24}
PAPER_TABLE_II = "whole vehicle design, HLS nodes included: fpgaDDS 44,939 CLB LUTs, 255 BRAM; CycloneDDS 134,252 LUTs"
NETWORKS = [(1, 1, None), (1, 1, 512), (2, 3, None), (2, 3, 512), (4, 4, None), (4, 4, 512)]
WIDTH, CLOCK_MHZ = 64, 100.0


def run_rtl_tests() -> bool:
    root = Path(__file__).resolve().parents[3]
    tests = root / "tests" / "unit" / "test_hw.py"
    if not tests.exists():
        print("[bench] the rtl tests are not beside this installation; skipped")
        return True
    if importlib.util.find_spec("pytest") is None:
        print("[bench] pytest is not installed (`make install-test` brings it): the exported Verilog's "
              "cross-check against the Amaranth scoreboard is skipped")
        return True
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-m", "rtl", str(tests)], cwd=root, check=False)
    return proc.returncode == 0


def table_one(quick: bool) -> list[dict[str, Any]]:
    rows = []
    for name, size in TABLE_I_SIZES.items():
        if quick and size > 200_000:
            continue
        cycles, simulator = transfer_cycles(1, 1, WIDTH, None, size, "icarus")
        row: dict[str, Any] = {"size": name, "bytes": size, "cycles": cycles, "ms": cycles / CLOCK_MHZ / 1000,
                               "simulator": simulator, "paper_fpgadds_ms": TABLE_I_PAPER_MS[name],
                               "paper_cyclonedds_ms": PAPER_CYCLONE_MS[name]}
        if size <= 12_288:
            row["amaranth_cycles"] = transfer_cycles(1, 1, WIDTH, None, size, "amaranth")[0]
        rows.append(row)
        print(f"[bench] {name}: {cycles:,} cycles")
    return rows


def table_two(quick: bool) -> list[dict[str, Any]]:
    rows = []
    for publishers, subscribers, fifo in NETWORKS[:2] if quick else NETWORKS:
        used = synthesize(publishers, subscribers, WIDTH, fifo)
        label = f"{publishers}x{subscribers}" + (f", FIFO {fifo}" if fifo else "")
        rows.append({"network": label, "luts": used.luts, "ffs": used.ffs, "bram36": used.bram36,
                     "lutram": used.lutram})
        print(f"[bench] {label}: {used}")
    return rows


def markdown(one: list[dict[str, Any]], two: list[dict[str, Any]]) -> str:
    lines = [f"### Table I shape: one message through a 1-to-1 hardware topic, {WIDTH}-bit, {CLOCK_MHZ:g} MHz, "
             "simulated", "",
             "| size | cycles | hetros at 100 MHz | fpgaDDS (paper) | CycloneDDS (paper) | "
             "CycloneDDS (paper) / hetros | Amaranth sim agrees |", "|---|---|---|---|---|---|---|"]
    for row in one:
        paper = row["paper_fpgadds_ms"]
        fpga = f"{paper:.2f} ms" if paper is not None else "<0.01 ms"
        speedup = f"{row['paper_cyclonedds_ms'] / row['ms']:.2f}x"
        agrees = "-" if "amaranth_cycles" not in row else ("yes" if row["amaranth_cycles"] == row["cycles"] else "NO")
        lines.append(f"| {row['size']} | {row['cycles']:,} | {row['ms']:.3f} ms | {fpga} | "
                     f"{row['paper_cyclonedds_ms']:.2f} ms | {speedup} | {agrees} |")
    lines += ["", "### Table II shape: Yosys estimate per topic network (synth_xilinx -family xcup -flatten)", "",
              format_resources([(r["network"], Resources(r["luts"], r["ffs"], r["bram36"], r["lutram"]))
                                for r in two]), "",
              f"Context, not a per-topic comparison: the paper's Table II is the {PAPER_TABLE_II}."]
    return "\n".join(lines)


def plot(one: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    sizes = [row["bytes"] for row in one]
    ax.loglog(sizes, [row["ms"] for row in one], "o-", label="hetros hardware topic (simulated, 100 MHz)")
    paper = [(row["bytes"], row["paper_fpgadds_ms"]) for row in one if row["paper_fpgadds_ms"]]
    ax.loglog(*zip(*paper, strict=True), "s--", label="fpgaDDS (paper, measured)")
    ax.loglog(sizes, [row["paper_cyclonedds_ms"] for row in one], "^:", label="CycloneDDS (paper, measured)")
    ax.set_xlabel("message size (bytes)")
    ax.set_ylabel("transfer time (ms)")
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="sizes up to 196 kB, two networks")
    parser.add_argument("--out", default="out/bench", help="folder for hw.md, hw.json, hw.png")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if not run_rtl_tests():
        print("[bench] the rtl tests failed: the figures below would not be trustworthy", file=sys.stderr)
        return 1
    one, two = table_one(args.quick), table_two(args.quick)
    text = markdown(one, two)
    print("\n" + text)
    (out / "hw.md").write_text(provenance() + "\n\n" + text + "\n")
    (out / "hw.json").write_text(json.dumps({"table_one": one, "table_two": two}, indent=1))
    plot(one, out / "hw.png")
    print(f"\nwrote {out / 'hw.md'}, {out / 'hw.json'}, {out / 'hw.png'}")
    return 0
