"""The mapping advisor against what it predicts: each example advised and verified by real launches.

    python benchmarks/advise.py [--out out/bench] [--examples lane_following,autoware,ball_on_plate]

Per example, ``hetros advise <project> --verify`` profiles the project as shipped, searches, and then
launches the top three mappings and the shipped one, measuring each chain from taps (ball on plate's
three times and autoware's twice, interleaved, the median of the launches' p50s). The table puts
each mapping's predicted chain p50 beside the measured one and their ratio (within 0.8-1.2 is the
advisor's target), and the advised mapping's measured p50 beside the shipped one's. It writes
advise.json, advise.md and advise.png (predicted against measured, the ±20 % band drawn).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from hetros_bench._provenance import provenance

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
# the chain each example is advised for, how long each of its launches runs (and its warm-up), and how
# many times each mapping is launched (interleaved; the median of their p50s): the shorter the chain, the
# more one launch differs from the next (ball on plate's, under a millisecond, by more than 20 %)
CHAINS = {
    "lane_following": ("alpha=/image_raw:/cmd_vel@30ms", 24.0, 6.0, 1),
    "autoware": ("steer=/current_pose:/twist_cmd@100ms", 20.0, 4.0, 2),
    "ball_on_plate": ("control=/ball_position:/servo_pwm@20ms", 10.0, 2.0, 3),
}


def advise(example: str, out: Path, examples: Path) -> dict[str, object]:
    chain, duration, warmup, rounds = CHAINS[example]
    folder = out / example
    command = [sys.executable, "-m", "hetros", "advise", str(examples / example / "project.yaml"), "--chain", chain,
               "--duration", str(duration), "--warmup", str(warmup), "--out", str(folder), "--verify",
               "--rounds", str(rounds)]
    done = subprocess.run(command, capture_output=True, text=True, check=False, timeout=1800)
    print(done.stdout, flush=True)
    if done.returncode not in (0, 1) or "the machine is busy" in done.stderr:
        raise SystemExit(f"{example}: hetros advise failed ({done.returncode}):\n{done.stderr[-3000:]}")
    summary: dict[str, object] = json.loads((folder / "advice.json").read_text(encoding="utf-8"))
    summary["chain"] = chain.split("=", 1)[0]
    return summary


def table(results: dict[str, dict[str, object]]) -> str:
    lines = ["| example | mapping | predicted p50 (ms) | measured p50 (ms) | each launch's p50 (ms) | "
             "predicted / measured |", "|---|---|---|---|---|---|"]
    for example, summary in results.items():
        chain = str(summary["chain"])
        predicted = summary["predicted"]
        measured = summary.get("measured", {})
        launches = summary.get("launch_p50s", {})
        assert isinstance(predicted, dict) and isinstance(measured, dict) and isinstance(launches, dict)
        for label, figures in predicted.items():
            found = measured.get(label, {}).get(chain)
            each = " / ".join(f"{v:.2f}" for v in launches.get(label, {}).get(chain, [])) or "-"
            ratio = f"{figures[chain] / found:.2f}" if found else "-"
            lines.append(f"| {example} | {label} | {figures[chain]:.1f} | {found:.2f} | {each} | {ratio} |" if found
                         else f"| {example} | {label} | {figures[chain]:.1f} | - | - | - |")
    return "\n".join(lines)


def plot(results: dict[str, dict[str, object]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(5.5, 5))
    top = 1.0
    for example, summary in results.items():
        chain = str(summary["chain"])
        predicted, measured = summary["predicted"], summary.get("measured", {})
        assert isinstance(predicted, dict) and isinstance(measured, dict)
        pairs = [(predicted[label][chain], measured[label][chain]) for label in predicted
                 if chain in measured.get(label, {})]
        if pairs:
            axis.scatter([m for _, m in pairs], [p for p, _ in pairs], label=example)
            top = max(top, *[max(p, m) for p, m in pairs])
    line = [0.0, top * 1.1]
    axis.plot(line, line, color="#444", linewidth=1)
    axis.fill_between(line, [v * 0.8 for v in line], [v * 1.2 for v in line], color="#999", alpha=0.2,
                      label="±20 %")
    axis.set_xlabel("measured chain p50 (ms)")
    axis.set_ylabel("predicted chain p50 (ms)")
    axis.set_title("hetros advise: predicted against measured\n(top three mappings and the shipped one)")
    axis.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out/bench")
    parser.add_argument("--examples", default=",".join(CHAINS))
    args = parser.parse_args(argv)
    out = Path(args.out) / "advise"
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="hetros-advise-") as name:  # the advised projects are written there
        examples = Path(name) / "examples"
        shutil.copytree(EXAMPLES, examples, ignore=shutil.ignore_patterns("__pycache__", "out"))
        results = {example: advise(example, out, examples) for example in args.examples.split(",")}
    report = table(results)
    print(report)
    (out.parent / "advise.md").write_text(provenance() + "\n\n" + report + "\n", encoding="utf-8")
    (out.parent / "advise.json").write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    plot(results, out.parent / "advise.png")
    print(f"\nwrote {out.parent / 'advise.md'}, {out.parent / 'advise.json'}, {out.parent / 'advise.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
