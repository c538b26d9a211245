"""What a new user meets in the first hour, tried as they would: each defect found from outside
once, now answered with one line that says what to do."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
# the module a distribution is imported as, where the names differ
_IMPORT_NAMES = {"PyYAML": "yaml", "annotated-types": "annotated_types", "typing-extensions": "typing_extensions",
                 "graphviz-pure": None}


def _python(code: str, *args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code), *args], capture_output=True, text=True,
                          timeout=120, check=False, cwd=ROOT, env=env)


def test_the_hardware_commands_say_how_to_get_their_tools() -> None:
    done = _python("""
        import sys
        sys.modules["amaranth"] = None  # as after `make install`: the rtl extra is not there
        from hetros.cli import main
        sys.exit(main(sys.argv[1:]))
    """, "hw", "build", str(EXAMPLES / "hw_topics" / "project.yaml"), "-o", "out/never")
    assert done.returncode == 1, done.stderr
    assert "Traceback" not in done.stderr
    assert "the hardware tools are not installed: run `make install-rtl`" in done.stderr


def test_the_hardware_benchmark_runs_without_pytest() -> None:
    done = _python("""
        import sys
        sys.modules["pytest"] = None  # `make install` brings no test tools
        from hetros_bench.hw import run_rtl_tests
        print(run_rtl_tests())
    """)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("True")
    assert "pytest is not installed (`make install-test` brings it)" in done.stdout


def test_every_core_dependency_is_used_and_graph_can_write_svg() -> None:
    dependencies = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]
    names = [re.split(r"[<>=\[ ]", dep, maxsplit=1)[0] for dep in dependencies]
    assert "graphviz-pure" in names, "`hetros graph --out x.svg` must work after `make install`"
    # the library, and the example `make run` launches after `make install` alone
    files = [*(ROOT / "src" / "hetros").rglob("*.py"), *(ROOT / "examples" / "lane_following").glob("*.py")]
    sources = "\n".join(p.read_text(encoding="utf-8") for p in files)
    for name in names:
        module = _IMPORT_NAMES.get(name, name.replace("-", "_").lower())
        if module is None:
            continue  # a program hetros runs, not a module it imports
        assert re.search(rf"^\s*(from|import) {module}\b", sources, re.M), f"{name} is a dependency nothing imports"


def test_a_ros2_service_without_a_server_names_the_domain(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""
        from hetros import Node, ServiceTimeoutError
        from hetros.interfaces.example_interfaces.srv import AddTwoInts

        def client(node: Node) -> None:
            adder = node.create_client(AddTwoInts, "/nobody_serves_this")
            try:
                adder.call(AddTwoInts.Request(a=1, b=2), timeout=7.0)
            except ServiceTimeoutError:
                node.log.info("no answer, as expected")
    """), encoding="utf-8")
    (tmp_path / "project.yaml").write_text(textwrap.dedent("""
        name: lonely
        targets: {main: {kind: thread}}
        nodes:
          client: {run: nodes:client, target: main, required: true,
                   clients: {/nobody_serves_this: example_interfaces/srv/AddTwoInts}}
        external:
          ros2: {import_services: [/nobody_serves_this]}
    """), encoding="utf-8")
    env = {**os.environ, "ROS_DOMAIN_ID": "97"}
    env.pop("CYCLONEDDS_URI", None)
    done = subprocess.run([sys.executable, "-m", "hetros", "launch", "project.yaml", "--duration", "30"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False, env=env)
    assert "is the ROS 2 server running on domain 97?" in done.stderr, done.stderr[-3000:]
    assert "domain None" not in done.stderr
