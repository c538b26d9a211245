from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from hetros import CheckError, ProjectError
from hetros.plan import Plan
from hetros.project import check, import_reconros, import_roslite, load_project, plan, template_from_sources

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

CASES = Path(__file__).resolve().parent.parent / "cases"

NODES = textwrap.dedent('''
    from hetros.interfaces.std_msgs.msg import String

    def pub(node):
        node.create_publisher(String, "/a")

    def sink(node):
        node.create_subscription(String, "/a", print)

    def sub(node):
        node.create_subscription(String, "/a", print)
        node.create_publisher(String, "/undeclared")
''')


def project(tmp_path: Path, text: str) -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    path = tmp_path / "project.yaml"
    path.write_text(textwrap.dedent(text))
    return path


@pytest.mark.slow
def test_examples_check_clean() -> None:
    for path in EXAMPLES.glob("*/project*.yaml"):
        report = check(load_project(path))
        assert report.errors == [], path


@pytest.mark.parametrize("case", sorted(p.stem for p in CASES.glob("warn_*.yaml")))
def test_doubtful_projects_plan_with_a_warning_naming_yaml_path_and_fix(case: str) -> None:
    """What ROS allows but is often a mistake (a subscriber nobody publishes to: waiting for `topic pub`,
    or a typo) plans, with a warning that says where and offers the fix."""
    path = CASES / f"{case}.yaml"
    expected = [line.removeprefix("# warn: ").strip()
                for line in path.read_text().splitlines() if line.startswith("# warn: ")]
    assert expected, f"case {case} states no expected warning"
    report = check(load_project(path))
    assert report.errors == []
    for fragment in expected:
        assert any(fragment in warning for warning in report.warnings), (fragment, report.warnings)
    plan(load_project(path))


@pytest.mark.parametrize("case", sorted(p.stem for p in CASES.glob("*.yaml") if not p.stem.startswith("warn_")))
def test_invalid_projects_report_yaml_path_and_fix(case: str) -> None:
    path = CASES / f"{case}.yaml"
    expected = [line.removeprefix("# expect: ").strip()
                for line in path.read_text().splitlines() if line.startswith("# expect: ")]
    assert expected, f"case {case} states no expected error"
    with pytest.raises((ProjectError, CheckError)) as info:
        plan(load_project(path))
    for fragment in expected:
        assert fragment in str(info.value), f"{fragment!r} not in:\n{info.value}"


def test_undeclared_endpoint_in_source_is_reported(tmp_path: Path) -> None:
    path = project(tmp_path, """
        name: t
        targets: {main: {kind: thread}}
        nodes:
          pub: {run: nodes:pub, target: main, publish: {/a: std_msgs/msg/String}}
          sub: {run: nodes:sub, target: main, subscribe: {/a: std_msgs/msg/String}}
    """)
    report = check(load_project(path))
    assert any("/undeclared" in e and "nodes.sub.publish" in e for e in report.errors), report.errors


def test_plan_picks_inproc_within_a_process_and_shm_across(tmp_path: Path) -> None:
    path = project(tmp_path, """
        name: t
        targets: {main: {kind: thread}, p1: {kind: process}, p2: {kind: process}}
        nodes:
          pub:  {run: nodes:pub, target: p1, publish: {/a: std_msgs/msg/String}}
          near: {run: nodes:sink, target: p1, subscribe: {/a: std_msgs/msg/String}}
          far:  {run: nodes:sink, target: p2, subscribe: {/a: std_msgs/msg/String}}
          home: {run: nodes:sink, target: main, subscribe: {/a: std_msgs/msg/String}}
        topics:
          /a: {history: keep_last, depth: 3}
    """)
    result = plan(load_project(path))
    transports = {(e.publisher, e.subscriber): e.transport for e in result.edges}
    assert transports == {("pub", "near"): "inproc", ("pub", "far"): "shm", ("pub", "home"): "shm"}
    assert result.channels["/a"].qos.depth == 3
    assert Plan.from_json(result.to_json()) == result


def test_threads_mapping_is_all_inproc() -> None:
    result = plan(load_project(EXAMPLES / "add_two_ints" / "project_threads.yaml"))
    assert {e.transport for e in result.edges} == {"inproc"}
    assert set(result.channels) == {"/add_two_ints/_request", "/add_two_ints/_reply/client"}


def test_roslite_map_imports_to_the_shipped_project() -> None:
    imported = import_roslite(EXAMPLES / "talker_listener" / "talker_listener.map")
    assert imported["targets"] == {"cluster1": {"kind": "process"}, "cluster2": {"kind": "process"}}
    assert imported["nodes"]["talker"] == {
        "run": "nodes:talker", "target": "cluster1", "publish": {"/chatter": "std_msgs/String"}}
    assert imported["nodes"]["listener2"]["subscribe"] == {"/chatter": "std_msgs/String"}
    shipped = load_project(EXAMPLES / "talker_listener" / "project.yaml").model
    assert {n: s.target for n, s in shipped.nodes.items()} == {
        n: s["target"] for n, s in imported["nodes"].items()}


def test_roslite_map_errors(tmp_path: Path) -> None:
    bad = tmp_path / "bad.map"
    bad.write_text("- name: a\n  cluster: 1\n  publish: [x, y]\n  publish_type: [std_msgs/String]\n")
    with pytest.raises(ProjectError, match="one type per topic"):
        import_roslite(bad)


def test_reconros_listing1_imports(tmp_path: Path) -> None:
    cfg = tmp_path / "build.cfg"
    cfg.write_text(textwrap.dedent("""
        [General]
        Name = SobelApp
        [ResourceGroup@ResourceGroupSobel]
        node_3 = roscpp, "Sobel"
        filter_service_msg = rossrvmsg, application_msgs, srv, SobelSrv
        filter_server = rossrvs, node_3, filter_service_msg, "sobelservice", 10000

        [ResourceGroup@ResourceGroupDIP]
        node_2 = roscpp, "DIP"
        filter_service_msg = rossrvmsg, application_msgs, srv, SobelSrv
        filter_client = rossrv, node_2, filter_service_msg, "sobelservice", 10000
        image_msg = rosmg, sensor_msgs, msg, Image
        sub = rossub, node_2, image_msg, "/image_raw", 10000
        pub = rospub, node_2, image_msg, "/image_filtered"
    """))
    data, _ = import_reconros(cfg)
    assert data["nodes"]["sobel"] == {"run": "nodes:sobel", "target": "resourcegroupsobel",
                                      "services": {"/sobelservice": "application_msgs/srv/SobelSrv"}}
    assert data["nodes"]["dip"]["clients"] == {"/sobelservice": "application_msgs/srv/SobelSrv"}
    assert data["nodes"]["dip"]["subscribe"] == {"/image_raw": "sensor_msgs/msg/Image"}
    assert data["nodes"]["dip"]["publish"] == {"/image_filtered": "sensor_msgs/msg/Image"}


def test_init_template_from_sources_checks_clean(tmp_path: Path) -> None:
    src = EXAMPLES / "talker_listener" / "nodes.py"
    data, _ = template_from_sources([src], src.parent, "tl")
    assert data["nodes"]["talker"]["publish"] == {"/chatter": "std_msgs/msg/String"}
    assert data["nodes"]["listener2"]["subscribe"] == {"/chatter": "std_msgs/msg/String"}


def test_a_node_module_that_prints_and_exits_at_import_is_named_not_a_traceback(tmp_path: Path) -> None:
    (tmp_path / "quitter.py").write_text('import os\nprint("[]", flush=True)\nos._exit(0)\n')
    (tmp_path / "printer.py").write_text('print("{}")\nprint("[1, 2]")\n\ndef node(n):\n    pass\n')
    for module, expected in (("quitter", "ended the interpreter before hetros could look at them"), ("printer", None)):
        path = tmp_path / f"{module}.yaml"
        path.write_text(f"name: q\nnodes:\n  a: {{run: '{module}:node', target: main}}\n")
        report = check(load_project(path))
        if expected is None:
            assert not report.errors, report.errors
        else:
            assert len(report.errors) == 1 and expected in report.errors[0] and "nodes.a.run" in report.errors[0]


def test_check_says_what_launch_refuses_of_a_bare_fpga_node(tmp_path: Path) -> None:
    """`hetros check` used to say OK where `hetros launch` refused: a node on an fpga target without hw:."""
    from hetros.project import check, load_project

    project = tmp_path / "project.yaml"
    project.write_text("name: bare\n"
                       "targets: {fpga0: {kind: fpga, clock_mhz: 100}, main: {kind: thread}}\n"
                       "nodes:\n"
                       "  a: {run: json:dumps, target: fpga0, publish: {/x: std_msgs/msg/String}}\n"
                       "  b: {run: json:dumps, target: main, subscribe: {/x: std_msgs/msg/String}}\n")
    report = check(load_project(project))
    assert any("node a sits on fpga target fpga0 without a hardware implementation" in w and
               "hetros launch` will refuse" in w for w in report.warnings), report.warnings
