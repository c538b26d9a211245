"""What one worker process costs: resident memory and import time before its nodes run, per kind of edge,
and the resident memory of the README talker/listener's workers while a real launch runs them.

    .venv/bin/python benchmarks/worker_footprint.py [--runs 5] [--out out/bench]

A worker loads only the transports its plan's edges use (``hetros.transport._seam``). For each
kind, a fresh interpreter does what ``python -m hetros.launch.launcher._worker`` does up to "ready":
imports the worker, reads the plan, opens every endpoint of its target. It reports its RSS
(VmRSS) and its import time (``-X importtime``, every top-level import summed), beside bare
interpreters that load what the transport stands on (numpy + iceoryx2 with one node;
cyclonedds with one participant), the floor a transport cannot go under. Medians of
``--runs``; ratios to the floor, since absolute figures depend on the machine.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from hetros.project import load_project, plan
from hetros.transport import remove_session_segments
from hetros_bench._provenance import provenance

_TALKER = textwrap.dedent('''
    from hetros import Node
    from hetros.interfaces.std_msgs.msg import String

    def talker(node: Node) -> None:
        node.create_publisher(String, "/chatter")

    def listener(node: Node) -> None:
        node.create_subscription(String, "/chatter", lambda m: None)
''')

_PROJECTS = {
    "shm-only worker": ("listener", """
        name: footprint
        targets: {a: {kind: process}, b: {kind: process}}
        nodes:
          talker:   {run: nodes:talker, target: a, publish: {/chatter: std_msgs/msg/String}}
          listener: {run: nodes:listener, target: b, subscribe: {/chatter: std_msgs/msg/String}}
        """),
    "worker with dds edges": ("listener", """
        name: footprint
        hosts: {here: {address: 127.0.0.1}, there: {address: 127.0.0.2}}
        targets: {a: {kind: process, host: there}, b: {kind: process, host: here}}
        nodes:
          talker:   {run: nodes:talker, target: a, publish: {/chatter: std_msgs/msg/String}}
          listener: {run: nodes:listener, target: b, subscribe: {/chatter: std_msgs/msg/String}}
        """),
}

_WORKER = textwrap.dedent('''
    import json, sys, threading, time
    start = time.perf_counter()
    import hetros.launch.launcher._worker
    from hetros.plan import Plan
    from hetros.runtime import Host
    plan = Plan.from_json(open(sys.argv[1]).read())
    if plan.hosts:
        plan = plan.on_host(sys.argv[3])
    host = Host(plan, sys.argv[2], "footprint", lambda *a: None, threading.Event())
    started = time.perf_counter() - start
    rss = int(open("/proc/self/status").read().split("VmRSS:")[1].split()[0])
    heavy = sorted(m for m in ("cyclonedds", "iceoryx2", "pydantic", "yaml", "hetros.transport.shm",
                               "hetros.transport.dds", "hetros.transport.tcpros") if m in sys.modules)
    host.graph.close()
    print(json.dumps({"rss_kb": rss, "start_ms": started * 1e3, "loaded": heavy}))
''')

_FLOORS = {
    "python + numpy + iceoryx2 node": textwrap.dedent('''
        import json, numpy, iceoryx2 as iox2
        node = iox2.NodeBuilder.new().create(iox2.ServiceType.Ipc)
        print(json.dumps({"rss_kb": int(open("/proc/self/status").read().split("VmRSS:")[1].split()[0])}))
    '''),
    "python + cyclonedds participant": textwrap.dedent('''
        import json
        from cyclonedds.domain import DomainParticipant
        participant = DomainParticipant(231)
        print(json.dumps({"rss_kb": int(open("/proc/self/status").read().split("VmRSS:")[1].split()[0])}))
    '''),
}


def _import_ms(stderr: str) -> float:
    """Every top-level import of ``-X importtime``'s report, summed (cumulative µs)."""
    total = 0
    for line in stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cumulative, name = line.split("|")
        if not name.startswith("   ") and name.strip() and cumulative.strip().isdigit():
            total += int(cumulative)
    return total / 1e3


_CHILD_ENV: dict[str, str] = dict(os.environ)


def _run(code: str, *args: str) -> dict[str, object]:
    done = subprocess.run([sys.executable, "-X", "importtime", "-c", code, *args], capture_output=True,
                          text=True, timeout=120, check=False, env=_CHILD_ENV)
    if done.returncode != 0:
        raise SystemExit(f"a measured process failed:\n{done.stderr[-2000:]}")
    result: dict[str, object] = json.loads(done.stdout.strip().splitlines()[-1])
    result["import_ms"] = _import_ms(done.stderr)
    return result


def measure(runs: int) -> dict[str, dict[str, object]]:
    rows: dict[str, dict[str, object]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "nodes.py").write_text(_TALKER, encoding="utf-8")
        for label, (node, text) in _PROJECTS.items():
            path = folder / f"{label.replace(' ', '_')}.yaml"
            path.write_text(textwrap.dedent(text), encoding="utf-8")
            the_plan = plan(load_project(path))
            plan_path = folder / f"{path.stem}.json"
            plan_path.write_text(the_plan.to_json(), encoding="utf-8")
            target = the_plan.nodes[node].target
            host = the_plan.targets[target].host
            try:
                samples = [_run(_WORKER, str(plan_path), target, host) for _ in range(runs)]
            finally:
                remove_session_segments("footprint")  # the launcher's part, as after every launch
            rows[label] = _summary(samples)
    for label, code in _FLOORS.items():
        rows[label] = _summary([_run(code) for _ in range(runs)])
    return rows


_EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "talker_listener" / "project.yaml"


def running_workers(runs: int) -> dict[str, dict[str, object]]:
    """The README's talker/listener as ``hetros launch`` runs it: each worker's VmRSS once its nodes have run
    for 4 s (the talker's process, and the two listeners' process), the median of ``runs`` launches."""
    seen: dict[str, list[dict[str, object]]] = {"running talker worker (launch)": [],
                                                 "running listeners worker (launch)": []}
    for _ in range(runs):
        with subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(_EXAMPLE), "--duration", "7"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=_CHILD_ENV) as launch:
            time.sleep(5.0)
            for pid in _children(launch.pid):
                command = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
                if b"hetros.launch.launcher._worker" not in command:
                    continue
                target = command[command.index(b"--target") + 1].decode()
                status = Path(f"/proc/{pid}/status").read_text()
                rss_kb = int(status.split("VmRSS:")[1].split()[0])
                role = "talker" if target == "cluster1" else "listeners"
                seen[f"running {role} worker (launch)"].append({"rss_kb": rss_kb, "import_ms": 0.0})
            launch.wait(60)
    return {label: _summary(samples) for label, samples in seen.items() if samples}


def _children(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                parent = int((entry / "stat").read_text().rpartition(")")[2].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            if parent == pid:
                found.append(int(entry.name))
    return found


def _summary(samples: list[dict[str, object]]) -> dict[str, object]:
    def median(key: str) -> float:
        return statistics.median(float(str(s[key])) for s in samples)
    row: dict[str, object] = {"rss_mb": median("rss_kb") / 1024, "import_ms": median("import_ms")}
    if "start_ms" in samples[0]:
        row["start_ms"] = median("start_ms")
        row["loaded"] = samples[0]["loaded"]
    return row


def render(rows: dict[str, dict[str, object]]) -> str:
    floor = rows["python + numpy + iceoryx2 node"]
    lines = ["| process | RSS MB | x floor | import ms | x floor | start ms | heavy modules loaded |",
             "|---|---:|---:|---:|---:|---:|---|"]
    for label, row in rows.items():
        rss, imp = float(str(row["rss_mb"])), float(str(row["import_ms"]))
        start = f"{float(str(row['start_ms'])):.0f}" if "start_ms" in row else ""
        loaded = ", ".join(row.get("loaded", [])) if isinstance(row.get("loaded"), list) else ""  # type: ignore[arg-type]
        lines.append(f"| {label} | {rss:.1f} | {rss / float(str(floor['rss_mb'])):.2f} | {imp:.0f} | "
                     f"{imp / float(str(floor['import_ms'])):.2f} | {start} | {loaded} |")
    return "\n".join(lines)


def plot(rows: dict[str, dict[str, object]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = list(rows)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 3.5))
    left.barh(labels, [float(str(rows[k]["rss_mb"])) for k in labels])
    left.set_xlabel("RSS (MB)")
    right.barh(labels, [float(str(rows[k]["import_ms"])) for k in labels])
    right.set_xlabel("import time (ms)")
    right.set_yticks([])
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--out", type=Path, default=Path("out/bench"))
    parser.add_argument("--source", type=Path, help="measure the workers of another checkout's src/ (a before/after)")
    args = parser.parse_args()
    if args.source is not None:
        _CHILD_ENV["PYTHONPATH"] = str(args.source.resolve())
    rows = measure(args.runs)
    rows.update(running_workers(min(args.runs, 3)))
    args.out.mkdir(parents=True, exist_ok=True)
    report = render(rows)
    print(report)
    (args.out / "worker_footprint.json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    (args.out / "worker_footprint.md").write_text(provenance() + "\n\n" + report + "\n", encoding="utf-8")
    plot(rows, args.out / "worker_footprint.png")
    print(f"wrote {args.out / 'worker_footprint.json'}, .md and .png")


if __name__ == "__main__":
    main()
