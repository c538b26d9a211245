"""Projects over several hosts: what check refuses, what the planner decides, what deploy runs."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from hetros import CheckError, LaunchError, ProjectError
from hetros.launch import deploy_commands, launch, local_host
from hetros.plan import Plan
from hetros.project import check, load_project, plan

NODES = textwrap.dedent('''
    from hetros.interfaces.std_msgs.msg import String

    def talker(node):
        node.create_publisher(String, "/chatter")

    def listener(node):
        node.create_subscription(String, "/chatter", print)
''')


def _project(tmp_path: Path, hosts: str, targets: str) -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    path = tmp_path / "project.yaml"
    path.write_text(textwrap.dedent("""
        name: spread
        hosts:
        {hosts}
        targets:
        {targets}
        nodes:
          talker: {{run: nodes:talker, target: a, publish: {{/chatter: std_msgs/msg/String}}}}
          listener: {{run: nodes:listener, target: b, subscribe: {{/chatter: std_msgs/msg/String}}}}
          echo: {{run: nodes:listener, target: c, subscribe: {{/chatter: std_msgs/msg/String}}}}
    """).format(hosts=textwrap.indent(hosts, "  "), targets=textwrap.indent(targets, "  ")))
    return path


HOSTS = "here: {address: 127.0.0.1}\nrobot: {address: 10.0.0.2, ssh: pi}"
TARGETS = "a: {kind: process}\nb: {kind: process, host: robot}\nc: {kind: thread}"


def test_edges_between_hosts_are_dds_and_the_rest_stay_on_their_host(tmp_path: Path) -> None:
    built = plan(load_project(_project(tmp_path, HOSTS, TARGETS)))
    assert {(e.publisher, e.subscriber): e.transport for e in built.edges} == {
        ("talker", "listener"): "dds", ("talker", "echo"): "shm"}
    assert built.targets["a"].host == "here"  # a target without host: is on the first host
    assert built.project_hash and len(built.project_hash) == 16
    here, robot = built.on_host("here"), built.on_host("robot")
    assert here.processes() == ["a"] and robot.processes() == ["b"]
    assert here.nodes_in("launcher") == ["echo"] and robot.nodes_in("launcher") == []
    assert Plan.from_json(here.to_json()) == here


def test_the_project_hash_covers_the_file(tmp_path: Path) -> None:
    path = _project(tmp_path, HOSTS, TARGETS)
    first = plan(load_project(path)).project_hash
    path.write_text(path.read_text() + "topics: {/chatter: {depth: 3}}\n")
    assert plan(load_project(path)).project_hash != first


@pytest.mark.parametrize(("hosts", "targets", "expected"), [
    (HOSTS, TARGETS.replace("host: robot", "host: moon"), r"targets\.b\.host: unknown host 'moon'; define it "
                                                         r"under hosts: \(known: here, robot\)"),
    ("here: {address: 127.0.0.1}\nthere: {address: 127.0.0.1}", TARGETS.replace("robot", "there"),
     r"hosts\.there\.address: 127\.0\.0\.1 is host here's address already"),
    ("my-host: {address: 10.0.0.9}\nrobot: {address: 10.0.0.2}", TARGETS,
     r"hosts\.my-host: a host name must be letters, digits and '_'"),
])
def test_check_refuses_bad_hosts(tmp_path: Path, hosts: str, targets: str, expected: str) -> None:
    with pytest.raises(CheckError, match=expected):
        plan(load_project(_project(tmp_path, hosts, targets)))


def test_a_host_without_hosts_section_and_a_bad_address_are_refused(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(NODES)
    path = tmp_path / "project.yaml"
    path.write_text("name: x\ntargets: {a: {kind: process, host: robot}}\n"
                    "nodes: {talker: {run: nodes:talker, target: a, publish: {/chatter: std_msgs/msg/String}}}\n")
    with pytest.raises(CheckError, match=r"targets\.a\.host: host 'robot' is not defined; name the machines under "
                                         r"hosts:"):
        plan(load_project(path))
    path.write_text("name: x\nhosts: {a: {address: 'not an address'}}\nnodes: {}\n")
    with pytest.raises(ProjectError, match=r"hosts\.a\.address.*must be an IP address or host name"):
        load_project(path)
    path.write_text("name: x\ntargets: {a: {kind: host}}\nnodes: {}\n")
    with pytest.raises(ProjectError, match=r"targets\.a\.kind"):
        load_project(path)


def test_this_machine_is_the_host_with_a_local_address(tmp_path: Path) -> None:
    built = plan(load_project(_project(tmp_path, HOSTS, TARGETS)))
    assert local_host(built) == "here"
    nowhere = plan(load_project(_project(tmp_path, HOSTS.replace("127.0.0.1", "10.0.0.7"), TARGETS)))
    with pytest.raises(LaunchError, match=r"which host is this machine\?.*none of its addresses.*--as <host>"):
        local_host(nowhere)
    with pytest.raises(LaunchError, match="--as moon: the project's hosts are here, robot"):
        launch(built, host="moon")
    robot = built.hosts["robot"].address
    with pytest.raises(LaunchError, match=rf"--as robot: its address {robot} is not one of this machine's.*"
                                          r"run this on robot's machine, or change hosts\.robot\.address"):
        launch(built, host="robot")


def test_check_says_when_no_host_is_this_machine(tmp_path: Path) -> None:
    nowhere = load_project(_project(tmp_path, HOSTS.replace("127.0.0.1", "10.0.0.7"), TARGETS))
    assert any("none of the hosts' addresses" in w and "is this machine's" in w for w in check(nowhere).warnings)
    assert not any("none of the hosts" in w for w in check(load_project(_project(tmp_path, HOSTS, TARGETS))).warnings)


def test_deploy_starts_this_host_directly_and_the_others_over_ssh(tmp_path: Path) -> None:
    path = _project(tmp_path, HOSTS, TARGETS)
    commands = deploy_commands(plan(load_project(path)), path, duration=5)
    assert commands["here"][1:] == ["-m", "hetros", "launch", str(path.resolve()), "--as", "here", "--duration", "5"]
    assert commands["robot"] == ["ssh", "-tt", "-o", "BatchMode=yes", "-l", "pi", "10.0.0.2",
                                 f"cd {tmp_path.resolve()} && python3 -m hetros launch {path.resolve()} --as robot "
                                 "--duration 5"]
    no_ssh = _project(tmp_path, HOSTS.replace(", ssh: pi", ""), TARGETS)
    with pytest.raises(LaunchError, match=r"host robot \(10\.0\.0\.2\) is not this machine and has no ssh user"):
        deploy_commands(plan(load_project(no_ssh)), no_ssh)


def test_hosts_and_a_ros2_bridge_need_different_domains(tmp_path: Path) -> None:
    path = _project(tmp_path, HOSTS, TARGETS)
    path.write_text(path.read_text() + "external: {ros2: {export: [/chatter]}}\n")
    with pytest.raises(CheckError, match=r"dds_domain: the edges between hosts and external: ros2: need different "
                                         r"DDS domains"):
        plan(load_project(path))
    path.write_text(path.read_text().replace("external: {ros2: {export: [/chatter]}}",
                                             "dds_domain: 7\nexternal: {ros2: {domain: 0, export: [/chatter]}}"))
    assert plan(load_project(path)).dds_domain == 7
