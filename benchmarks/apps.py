"""Every reference application in each of its mappings: node times and end-to-end times.

    python benchmarks/apps.py [--out out/bench] [--apps lane_following,sobel,...]

Per application it prints, in the shape of ReconROS Table 5 and fpgaDDS Table III, the time
each node spends per message (mean ± std, from the runtime's own per-endpoint accounting) and
the application's end-to-end figure (chain latency, round trip, control period) for the
process mapping and the all-threads mapping side by side, and writes apps.json.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

from hetros_bench._provenance import provenance

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
MAPPINGS = {"processes": "project.yaml", "threads": "project_threads.yaml"}
# examples without a required node run for a fixed time
DURATION = {"talker_listener": 3.0, "add_two_ints": 3.0}
NODE_TIME = re.compile(r"\[(\w+)\]: node time on (\S+): ([\d.]+) ± ([\d.]+) ms per message over (\d+)")
END_TO_END = [
    re.compile(r"\[\w+\]: (chain alpha latency) ([\d.]+) ± ([\d.]+) ms"),
    re.compile(r"\[\w+\]: (control period) ([\d.]+) ± ([\d.]+) ms"),
    re.compile(r"\[\w+\]: .*(chain latency) ([\d.]+) ± ([\d.]+) ms"),
    re.compile(r"\[\w+\]: (round trip +\d+ B): +([\d.]+) ± +([\d.]+) µs"),
]


def run(app: str, mapping: str) -> dict[str, object]:
    project = EXAMPLES / app / MAPPINGS[mapping]
    start = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "hetros", "launch", str(project), "--duration",
                           str(DURATION.get(app, 300.0)), "--node-times"], capture_output=True, text=True, check=False,
                          timeout=600, cwd=EXAMPLES.parent)
    wall = time.monotonic() - start
    nodes = [{"node": m[0], "endpoint": m[1], "mean_ms": float(m[2]), "std_ms": float(m[3]), "count": int(m[4])}
             for m in NODE_TIME.findall(proc.stderr)]
    ends = []
    for pattern in END_TO_END:
        for label, mean, std in pattern.findall(proc.stderr):
            unit = "µs" if "round trip" in label else "ms"
            ends.append({"what": " ".join(label.split()), "mean": float(mean), "std": float(std), "unit": unit})
    return {"app": app, "mapping": mapping, "exit_code": proc.returncode, "wall_s": wall, "nodes": nodes,
            "end_to_end": ends, "error": proc.stderr[-500:] if proc.returncode else ""}


def table(app: str, results: dict[str, dict[str, object]]) -> str:
    lines = [f"### {app}", "", "| node (endpoint) | " + " | ".join(results) + " |", "|---|" + "---|" * len(results)]
    keys: list[tuple[str, str]] = []
    for result in results.values():
        for row in result["nodes"]:  # type: ignore[attr-defined]
            key = (row["node"], row["endpoint"])
            if key not in keys:
                keys.append(key)
    for node, endpoint in keys:
        cells = []
        for result in results.values():
            match = [r for r in result["nodes"] if (r["node"], r["endpoint"]) == (node, endpoint)]  # type: ignore[attr-defined]
            cells.append(f"{match[0]['mean_ms']:.2f} ± {match[0]['std_ms']:.2f} ms" if match else "-")
        lines.append(f"| {node} ({endpoint}) | " + " | ".join(cells) + " |")
    whats: list[str] = []
    for result in results.values():
        for row in result["end_to_end"]:  # type: ignore[attr-defined]
            if row["what"] not in whats:
                whats.append(row["what"])
    for what in whats:
        cells = []
        for result in results.values():
            match = [r for r in result["end_to_end"] if r["what"] == what]  # type: ignore[attr-defined]
            cells.append(f"{match[0]['mean']:.1f} ± {match[0]['std']:.1f} {match[0]['unit']}" if match else "-")
        lines.append(f"| **{what}** | " + " | ".join(cells) + " |")
    lines.append("| run time (wall) | " + " | ".join(f"{r['wall_s']:.1f} s" for r in results.values()) + " |")
    failed = [m for m, r in results.items() if r["exit_code"]]
    if failed:
        lines.append(f"\nfailed in: {', '.join(failed)}")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="out/bench")
    parser.add_argument("--apps", help="comma-separated subset of the examples")
    args = parser.parse_args()
    apps = args.apps.split(",") if args.apps else sorted(
        p.name for p in EXAMPLES.iterdir() if (p / "project.yaml").exists() and (p / "project_threads.yaml").exists())
    everything = []
    report = []
    for app in apps:
        results = {mapping: run(app, mapping) for mapping in MAPPINGS}
        everything.extend(results.values())
        text = table(app, results)
        report.append(text)
        print(text + "\n", flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "apps.json").write_text(json.dumps(everything, indent=1))
    (out / "apps.md").write_text(provenance() + "\n\n" + "\n\n".join(report) + "\n")
    print(f"wrote {out / 'apps.json'} and {out / 'apps.md'}")
    return 1 if any(r["exit_code"] for r in everything) else 0


if __name__ == "__main__":
    sys.exit(main())
