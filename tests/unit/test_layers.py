"""The architecture as the import graph: layers import downward only, the runtime names no
transport, msg has no import circle, and a worker loads only the transports its edges use."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
import textwrap
import threading
from pathlib import Path
from typing import Any, ClassVar

import pytest

from hetros.msg import registry
from hetros.plan import ChannelPlan, EdgePlan, NodePlan, Plan, TargetPlan
from hetros.runtime import Graph
from hetros.transport import (
    DEFAULT_QOS,
    Endpoint,
    InprocTransport,
    Reader,
    Wake,
    Writer,
    register,
    registered,
    remove_session_segments,
    transport_class,
)

SRC = Path(__file__).resolve().parents[2] / "src" / "hetros"
TRANSPORT_PACKAGES = sorted(p.name for p in (SRC / "transport").iterdir() if (p / "__init__.py").exists())
# what each package may import of hetros (besides itself and the modules below all: errors, log, net, process, QoS)
ALLOWED = {
    "msg": set(),
    "plan": set(),
    "transport": {"msg", "plan"},
    "runtime": {"msg", "plan", "transport"},
    "hw": {"msg", "plan"},
    "project": {"msg", "plan", "transport", "hw"},
}
BASE = {"_errors", "_files", "_lazy", "_log", "_net", "_paths", "_process", "_qos", "_signals"}


def _imports(path: Path) -> list[tuple[str, int, str]]:
    """``(absolute module, line, where)`` of every hetros import in ``path``; where is "module"
    (runs on import), "typing" (under ``if TYPE_CHECKING:``) or "function"."""
    package = ".".join(path.relative_to(SRC.parent).with_suffix("").parts[:-1])
    tree = ast.parse(path.read_text(encoding="utf-8"))
    top = {id(node) for node in tree.body}
    typing = {id(child) for node in tree.body if isinstance(node, ast.If) for child in node.body}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            names = [f"{module}.{alias.name}" for alias in node.names]
            where = "module" if id(node) in top else "typing" if id(node) in typing else "function"
            found += [(name, node.lineno, where) for name in [module, *names]]
        elif isinstance(node, ast.Import):
            where = "module" if id(node) in top else "typing" if id(node) in typing else "function"
            found += [(alias.name, node.lineno, where) for alias in node.names]
    return [item for item in found if item[0].startswith("hetros")]


def _files(package: str) -> list[Path]:
    return sorted((SRC / package).rglob("*.py"))


def test_the_runtime_names_no_transport() -> None:
    """Adding a transport touches transport/<name>/ and one registration: the runtime only
    reaches transports through ``hetros.transport``'s seam."""
    offending = [f"{path.relative_to(SRC)}:{line}: {module}"
                 for path in _files("runtime") for module, line, _ in _imports(path)
                 for name in TRANSPORT_PACKAGES if module.startswith(f"hetros.transport.{name}")]
    assert not offending, "runtime/ imports a transport sub-package:\n" + "\n".join(offending)
    assert TRANSPORT_PACKAGES == ["dds", "shm", "tcpros"]


@pytest.mark.parametrize("package", sorted(ALLOWED))
def test_layers_import_downward_only(package: str) -> None:
    allowed = ALLOWED[package] | BASE | {package}
    offending = []
    for path in _files(package):
        for module, line, _ in _imports(path):
            parts = module.split(".")
            layer = len(parts) > 1 and ((SRC / parts[1]).is_dir() or (SRC / f"{parts[1]}.py").exists())
            if layer and parts[1] not in allowed:
                offending.append(f"{path.relative_to(SRC)}:{line}: {module}")
    assert not offending, f"{package}/ imports a layer above it:\n" + "\n".join(sorted(set(offending)))


def test_no_package_reaches_into_another_packages_private_modules() -> None:
    """What a package shares it exports (``hetros.<package>.<name>``, loaded lazily where a worker must not
    pay for it); ``hetros.<package>._module`` is that package's own business."""
    offending = set()
    for path in sorted(SRC.rglob("*.py")):
        relative = path.relative_to(SRC)
        own = relative.parts[0] if len(relative.parts) > 1 else ""
        for module, line, _ in _imports(path):
            parts = module.split(".")
            private = [part for part in parts[2:] if part.startswith("_") and not part.startswith("__")]
            if len(parts) > 2 and parts[1] != own and not parts[1].startswith("_") and private:
                offending.add(f"{relative}:{line}: hetros.{parts[1]}...{private[0]}")
    assert not offending, "imports of another package's private modules or names (export them instead):\n" + \
        "\n".join(sorted(offending))


def _assert_no_circle(graph: dict[str, set[str]], starts: list[str]) -> None:
    """Fails naming the first import circle found from ``starts`` in ``graph`` (module -> what it imports)."""
    done: set[str] = set()

    def visit(module: str, trail: list[str]) -> None:
        if module in trail:
            raise AssertionError("import circle: " + " -> ".join([*trail[trail.index(module):], module]))
        if module in done:
            return
        for other in graph.get(module, ()):
            visit(other, [*trail, module])
        done.add(module)

    for module in starts:
        visit(module, [])


def test_msg_has_no_import_circle() -> None:
    """Imports between msg's modules form no cycle, counting those inside functions (loaded on first use, so
    that a worker does not pay for the .msg parser or rosbags' type system): lazy is for cost, never a way
    around a circle."""
    graph: dict[str, set[str]] = {}
    for path in _files("msg"):
        me = path.stem
        graph[me] = set()
        for module, _line, where in _imports(path):
            parts = module.split(".")
            if parts[:2] == ["hetros", "msg"] and len(parts) > 2 and (SRC / "msg" / f"{parts[2]}.py").exists():
                if where in ("module", "function"):
                    graph[me].add(parts[2])
    _assert_no_circle(graph, list(graph))


# hw's sub-packages, lowest first: each imports only those before it (nodes.py and reference.py, the
# public faces of the designs, sit with them)
HW_ORDER = ["streams", "designs", "top", "sim", "flow"]


def _hw_package(path_or_module: str) -> str | None:
    parts = path_or_module.split(".")
    if parts[:2] != ["hetros", "hw"] or len(parts) < 3:
        return None
    return "designs" if parts[2] in ("nodes", "reference") else parts[2] if parts[2] in HW_ORDER else None


def test_hw_sub_packages_import_one_way_and_hw_has_no_import_circle() -> None:
    """streams <- designs <- top <- sim <- flow, counting imports inside functions; and no circle between
    hw's modules (the builder and the nodes once imported each other through five files)."""
    offending = []
    graph: dict[str, set[str]] = {}
    for path in _files("hw"):
        me = ".".join(path.relative_to(SRC.parent).with_suffix("").parts)
        mine = _hw_package(me)
        graph[me] = set()
        for module, line, where in _imports(path):
            theirs = _hw_package(module)
            if where == "typing" or theirs is None:
                continue
            if mine is not None and HW_ORDER.index(theirs) > HW_ORDER.index(mine):
                offending.append(f"{path.relative_to(SRC)}:{line}: {mine} imports {module} ({theirs})")
            target = module if (SRC.parent / (module.replace(".", "/") + ".py")).exists() else \
                module.rsplit(".", 1)[0]
            if (SRC.parent / (target.replace(".", "/") + ".py")).exists() and target != me:
                graph[me].add(target)
    assert not offending, "hw's sub-packages import upward:\n" + "\n".join(offending)
    _assert_no_circle(graph, [m for m in graph if not m.endswith("__init__")])


_WORKER = textwrap.dedent('''
    import json, sys, threading
    import hetros.launch.launcher._worker
    from hetros.plan import Plan
    from hetros.runtime import Host
    plan = Plan.from_json(open(sys.argv[1]).read())
    if plan.hosts:
        plan = plan.on_host(sys.argv[3])
    host = Host(plan, sys.argv[2], sys.argv[4], lambda *a: None, threading.Event())
    loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("cyclonedds", "iceoryx2", "pydantic", "yaml")
                    or m.startswith("hetros.transport.") or m.startswith("hetros.project"))
    host.graph.close()
    print(json.dumps(loaded))
''')


def _worker_modules(tmp_path: Path, project: str, node: str, session: str) -> set[str]:
    from hetros.project import load_project, plan

    (tmp_path / "nodes.py").write_text(textwrap.dedent('''
        from hetros.interfaces.std_msgs.msg import String
        def talker(node): node.create_publisher(String, "/chatter")
        def listener(node): pass
    '''), encoding="utf-8")
    (tmp_path / "p.yaml").write_text(textwrap.dedent(project), encoding="utf-8")
    the_plan = plan(load_project(tmp_path / "p.yaml"))
    (tmp_path / "plan.json").write_text(the_plan.to_json(), encoding="utf-8")
    target = the_plan.nodes[node].target
    try:
        done = subprocess.run([sys.executable, "-c", _WORKER, str(tmp_path / "plan.json"), target,
                               the_plan.targets[target].host, session], capture_output=True, text=True, timeout=120)
    finally:
        remove_session_segments(session)  # the launcher's part, as after every launch
    assert done.returncode == 0, done.stderr
    return {m.rsplit("._", 1)[0] for m in json.loads(done.stdout.splitlines()[-1])}


def test_a_shm_only_worker_loads_neither_dds_nor_ros1_nor_the_project_model(tmp_path: Path,
                                                                           shm_session: str) -> None:
    loaded = _worker_modules(tmp_path, """
        name: lean
        targets: {a: {kind: process}, b: {kind: process}}
        nodes:
          talker:   {run: nodes:talker, target: a, publish: {/chatter: std_msgs/msg/String}}
          listener: {run: nodes:listener, target: b, subscribe: {/chatter: std_msgs/msg/String}}
        """, "listener", shm_session)
    assert "hetros.transport.shm" in loaded and "iceoryx2" in loaded
    assert not {m for m in loaded if m.startswith(("cyclonedds", "hetros.transport.dds", "hetros.transport.tcpros",
                                                     "pydantic", "yaml", "hetros.project"))}, loaded


def test_a_worker_with_only_dds_edges_loads_no_shared_memory(tmp_path: Path, shm_session: str) -> None:
    loaded = _worker_modules(tmp_path, """
        name: lean
        hosts: {here: {address: 127.0.0.1}, there: {address: 127.0.0.2}}
        targets: {a: {kind: process, host: there}, b: {kind: process, host: here}}
        nodes:
          talker:   {run: nodes:talker, target: a, publish: {/chatter: std_msgs/msg/String}}
          listener: {run: nodes:listener, target: b, subscribe: {/chatter: std_msgs/msg/String}}
        """, "listener", shm_session)
    assert "hetros.transport.dds" in loaded and "cyclonedds" in loaded
    unwanted = ("iceoryx2", "hetros.transport.shm", "hetros.transport.tcpros")
    assert not {m for m in loaded if m.startswith(unwanted)}, loaded


class _CountingTransport(InprocTransport):
    """A new kind of edge, as a tap or recorder would be: in-process delivery that counts what it opened."""

    kind = "counted"
    opened: ClassVar[list[str]] = []

    def open_writer(self, endpoint: Endpoint) -> Any:
        self.opened.append(f"writer {endpoint.name} {endpoint.node} {[e.subscriber for e in endpoint.edges]}")
        return super().open_writer(endpoint)

    def open_reader(self, endpoint: Endpoint, wake: Wake) -> Any:
        self.opened.append(f"reader {endpoint.name} {endpoint.node} {[e.publisher for e in endpoint.edges]}")
        return super().open_reader(endpoint, wake)


def test_a_new_transport_is_one_registration_and_the_runtime_opens_it_from_the_plan() -> None:
    register("counted", f"{__name__}:_CountingTransport")
    assert "counted" in registered() and transport_class("counted") is _CountingTransport
    types = registry()
    plan = Plan(
        name="seam", root=".", message_paths=(),
        targets={"t": TargetPlan("t", "thread")},
        nodes={"a": NodePlan("a", "x:a", "t", publish={"/x": "std_msgs/msg/Int32"}),
               "b": NodePlan("b", "x:b", "t", subscribe={"/x": "std_msgs/msg/Int32"})},
        channels={"/x": ChannelPlan("/x", "std_msgs/msg/Int32", "topic", DEFAULT_QOS, ("a",), ("b",))},
        edges=(EdgePlan("/x", "a", "b", "counted"),),  # type: ignore[arg-type]
    )
    graph = Graph(plan, types=types, stop=threading.Event())
    try:
        graph.prepare(["a", "b"])
        reader: Reader = graph.open_reader("/x", "b", "std_msgs/msg/Int32", lambda: None)
        writer: Writer = graph.open_writer("/x", "a", "std_msgs/msg/Int32")
        writer.write(types.get("std_msgs/msg/Int32")(data=7))
        assert reader.taker()().data == 7
        assert _CountingTransport.opened == ["reader /x b ['a']", "writer /x a ['b']"]
    finally:
        graph.close()


def test_an_unregistered_kind_is_refused_with_the_registered_ones_named() -> None:
    from hetros import TransportError

    with pytest.raises(TransportError, match=r"no transport is registered for edges of kind 'carrier_pigeon' "
                                             r"\(registered: .*dds.*shm"):
        transport_class("carrier_pigeon")


LONG_FUNCTIONS = Path(__file__).resolve().parents[1] / "data" / "long_functions.txt"


def test_no_function_in_src_grows_past_sixty_lines() -> None:
    """The rule for project/ (below) over all of src/hetros: the functions over 60 lines today are listed in
    tests/data/long_functions.txt, which may only shrink; one not listed, or a listed one split, fails."""
    listed = {line.strip() for line in LONG_FUNCTIONS.read_text(encoding="utf-8").splitlines()
              if line.strip() and not line.startswith("#")}
    found = {f"{path.relative_to(SRC)}:{node.name}"
             for path in sorted(SRC.rglob("*.py")) for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
             if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.end_lineno is not None
             and node.end_lineno - node.lineno + 1 > 60}
    assert not found - listed, f"functions grown past 60 lines (split them): {sorted(found - listed)}"
    assert not listed - found, f"split, or gone: remove from {LONG_FUNCTIONS.name}: {sorted(listed - found)}"


def test_no_function_in_project_is_over_sixty_lines() -> None:
    """The rules every feature touches stay readable: a check is a named rule, the planner a list of steps
    (``project/_checks.py``, ``project/_planner.py``); a function that grows past 60 lines is split."""
    long = [f"{path.relative_to(SRC)}:{node.lineno} {node.name} ({node.end_lineno - node.lineno + 1} lines)"
            for path in _files("project") for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and node.end_lineno is not None
            and node.end_lineno - node.lineno + 1 > 60]
    assert not long, "functions over 60 lines in project/:\n" + "\n".join(long)
