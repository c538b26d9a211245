from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"


def hetros(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "hetros", *args], capture_output=True, text=True,
                          timeout=60, check=False, cwd=cwd)


def test_check_ok_and_errors_exit_1() -> None:
    ok = hetros("check", str(EXAMPLES / "talker_listener" / "project.yaml"))
    assert ok.returncode == 0 and "OK" in ok.stdout
    bad = hetros("check", str(ROOT / "tests" / "cases" / "type_mismatch.yaml"))
    assert bad.returncode == 1
    assert "topic /x is declared with different types" in bad.stderr


def test_graph_prints_both_graphs_and_writes_dot_and_svg(tmp_path: Path) -> None:
    result = hetros("graph", str(EXAMPLES / "talker_listener" / "project.yaml"), "--out", str(tmp_path / "g"))
    assert result.returncode == 0, result.stderr
    assert "computation graph" in result.stdout and "architecture graph" in result.stdout
    assert "talker -> listener  /chatter  via shm" in result.stdout
    assert (tmp_path / "g.dot").read_text().startswith("digraph")
    assert "<svg" in (tmp_path / "g.svg").read_text()


def test_import_roslite_writes_a_project_that_checks(tmp_path: Path) -> None:
    out = tmp_path / "imported.yaml"
    src = EXAMPLES / "talker_listener"
    result = hetros("import", "roslite", str(src / "talker_listener.map"), "-o", str(out))
    assert result.returncode == 0, result.stderr
    (tmp_path / "nodes.py").write_text((src / "nodes.py").read_text())
    data = yaml.safe_load(out.read_text())
    assert data["nodes"]["listener"]["target"] == "cluster2"
    checked = hetros("check", str(out))
    assert checked.returncode == 0, checked.stderr


def test_init_writes_a_template(tmp_path: Path) -> None:
    out = tmp_path / "p.yaml"
    result = hetros("init", str(EXAMPLES / "add_two_ints" / "nodes.py"), "-o", str(out))
    assert result.returncode == 0, result.stderr
    data = yaml.safe_load(out.read_text())
    assert data["nodes"]["server"]["services"] == {"/add_two_ints": "example_interfaces/srv/AddTwoInts"}


def test_msg_show_prints_nested_definitions() -> None:
    result = hetros("msg", "show", "sensor_msgs/msg/Image")
    assert result.returncode == 0
    assert "uint8[] data" in result.stdout and "MSG: std_msgs/Header" in result.stdout
    srv = hetros("msg", "show", "example_interfaces/srv/AddTwoInts")
    assert srv.stdout.split() == ["int64", "a", "int64", "b", "---", "int64", "sum"]
    unknown = hetros("msg", "show", "nope/msg/Nothing")
    assert unknown.returncode == 1 and "unknown message type" in unknown.stderr


def test_msg_build_writes_importable_typed_modules(tmp_path: Path) -> None:
    pkg = tmp_path / "src" / "geo_pkg"
    (pkg / "msg").mkdir(parents=True)
    (pkg / "srv").mkdir()
    (pkg / "msg" / "Pose2.msg").write_text("float64 x\nfloat64 y\nfloat64 theta\n")
    (pkg / "srv" / "Go.srv").write_text("Pose2 target\n---\nbool ok\n")
    out = tmp_path / "gen"
    result = hetros("msg", "build", str(pkg), "-o", str(out))
    assert result.returncode == 0, result.stderr
    text = (out / "geo_pkg" / "msg.py").read_text()
    assert text.startswith("# DO NOT EDIT")
    probe = subprocess.run(
        [sys.executable, "-c", "from geo_pkg.msg import Pose2; from geo_pkg.srv import Go_Request;"
         "p = Pose2(x=1.0); print(p.x, Go_Request().target.theta)"],
        capture_output=True, text=True, cwd=out, check=False, timeout=60,
    )
    assert probe.returncode == 0, probe.stderr
    assert probe.stdout.split() == ["1.0", "0.0"]


def test_msg_layout_prints_offsets() -> None:
    result = hetros("msg", "layout", "geometry_msgs/msg/PoseWithCovariance")
    assert result.returncode == 0
    assert "fixed size, 344 bytes" in result.stdout
    assert "56    288  float64[36]  covariance" in result.stdout
    assert result.stdout.splitlines()[-1] in ("codec: compiled (hetros.msg._ccdr)",
                                              "codec: generated Python (the C extension is not built)",
                                              "codec: generated Python (HETROS_PURE_PYTHON is set)")


def test_msg_build_handles_python_names_and_refuses_invalid_type_names(tmp_path: Path) -> None:
    pkg = tmp_path / "src" / "odd_pkg"
    (pkg / "msg").mkdir(parents=True)
    (pkg / "msg" / "Odd.msg").write_text("int32 self\nint32 np\nfloat64[] copy\nint32 class\nint32 x 7\n")
    out = tmp_path / "gen"
    result = hetros("msg", "build", str(pkg), "-o", str(out))
    assert result.returncode == 0, result.stderr
    stub = (out / "odd_pkg" / "msg.py").read_text()
    compile(stub, "msg.py", "exec")
    probe = subprocess.run(
        [sys.executable, "-c", "from odd_pkg.msg import Odd; o = Odd(self=1, np=2, class_=3);"
         "print(o.self, o.np, o.class_, o.x, o.copy.size)"],
        capture_output=True, text=True, cwd=out, check=False, timeout=60,
    )
    assert probe.returncode == 0, probe.stderr
    assert probe.stdout.split() == ["1", "2", "3", "7", "0"]
    (pkg / "msg" / "1Foo.msg").write_text("int32 x\n")
    bad = hetros("msg", "build", str(pkg), "-o", str(tmp_path / "gen2"))
    assert bad.returncode == 1
    assert "1Foo.msg:1: '1Foo' is not a valid type name" in bad.stderr
    assert not (tmp_path / "gen2").exists()


def test_msg_show_lists_action_parts() -> None:
    result = hetros("msg", "show", "example_interfaces/action/Fibonacci_SendGoal_Request")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[:2] == ["unique_identifier_msgs/msg/UUID goal_id", "example_interfaces/action/Fibonacci_Goal goal"]
    assert "MSG: unique_identifier_msgs/msg/UUID" in result.stdout and "int32 order" in result.stdout


def test_an_example_missing_its_extra_says_what_to_install(tmp_path: Path) -> None:
    """After `make install` alone (no scikit-learn), check names the missing extra in one line."""
    blocker = tmp_path / "sklearn"
    blocker.mkdir()
    (blocker / "__init__.py").write_text("raise ModuleNotFoundError(\"No module named 'sklearn'\")\n")
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    result = subprocess.run([sys.executable, "-m", "hetros", "check",
                             str(ROOT / "examples" / "digit_classifier" / "project.yaml")],
                            capture_output=True, text=True, timeout=120, env=env, check=False)
    assert result.returncode == 1
    assert "run `.venv/bin/pip install -e '.[examples]'`" in result.stderr, result.stderr
    assert "nodes.client.run" in result.stderr
