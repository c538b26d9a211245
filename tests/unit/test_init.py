"""`hetros init` finds every node of every shipped example, with the endpoints its project declares."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from hetros.project import ros_template, template_from_sources

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SECTIONS = ("publish", "subscribe", "services", "clients", "actions", "action_clients")


def _declared(example: Path) -> dict[str, dict[str, set[str]]]:
    """function of nodes.py -> section -> endpoint names, over every project file of the example."""
    found: dict[str, dict[str, set[str]]] = {}
    for project in sorted(example.glob("project*.yaml")):
        for spec in yaml.safe_load(project.read_text(encoding="utf-8")).get("nodes", {}).values():
            module, _, function = spec["run"].partition(":")
            if module != "nodes":
                continue
            entry = found.setdefault(function, {section: set() for section in SECTIONS})
            for section in SECTIONS:
                entry[section] |= set(spec.get(section, {}))
    return found


@pytest.mark.parametrize("example", sorted(p.parent.name for p in EXAMPLES.glob("*/nodes.py")))
def test_init_finds_every_node_and_endpoint_of_the_shipped_examples(example: str) -> None:
    folder = EXAMPLES / example
    template, unresolved = template_from_sources([folder / "nodes.py"], folder, example)
    declared = _declared(folder)
    assert set(template["nodes"]) == set(declared), unresolved
    for function, sections in declared.items():
        scanned = template["nodes"][function]
        for section in SECTIONS:
            assert set(scanned.get(section, {})) == sections[section], (function, section, unresolved)


def test_what_init_cannot_follow_is_named_with_file_and_line(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(
        "from hetros.interfaces.std_msgs.msg import String\n"
        "def relay(node, topic):\n"
        "    node.create_publisher(String, topic)\n"
        "def chooser(node):\n"
        "    node.create_subscription(String, node.get_parameter('topic'))\n"
        "def left(node):\n"
        "    relay(node, '/left')\n", encoding="utf-8")
    template, unresolved = template_from_sources([tmp_path / "nodes.py"], tmp_path, "t")
    assert set(template["nodes"]) == {"chooser", "left"}  # relay needs more than the node: a helper
    assert template["nodes"]["left"]["publish"] == {"/left": "std_msgs/msg/String"}
    assert unresolved == ["nodes.py:5: create_subscription(..., node.get_parameter('topic')) names its subscribe "
                          "endpoint at run time; add it to nodes.chooser.subscribe by hand"]


ROS2_EXAMPLES = Path(__file__).resolve().parents[1] / "data" / "ros2_examples" / "rclpy"
TUTORIALS = Path(__file__).resolve().parents[1] / "data" / "ros_tutorials" / "rospy_tutorials"


def test_init_reads_an_rclpy_package_from_its_entry_points() -> None:
    from hetros.project import ros_template

    project, notes = ros_template([ROS2_EXAMPLES / "topics" / "minimal_publisher"], "p", Path.cwd())
    assert notes == []
    # setup.py's console_scripts, one written as two adjacent strings; all three name their node the same, so
    # each is keyed by its console script, as `ros2 run` knows it (and its node name is kept as name:)
    assert set(project["nodes"]) == {"publisher_old_school", "publisher_local_function", "publisher_member_function"}
    runs = {n["run"] for n in project["nodes"].values()}
    assert runs == {f"examples_rclpy_minimal_publisher.{m}:main"
                    for m in ("publisher_old_school", "publisher_local_function", "publisher_member_function")}
    for key, node in project["nodes"].items():
        assert node["publish"] == {"topic": "std_msgs/msg/String"}
        assert node["target"] == key and project["targets"][key] == {"kind": "process"}
        assert node.get("name", key) == "minimal_publisher"
    assert project["topics"] == {"/topic": {"history": "keep_last", "depth": 10}}


def test_init_follows_a_main_into_the_package_and_names_a_composition_after_its_entry_point() -> None:
    from hetros.project import ros_template

    project, _ = ros_template([ROS2_EXAMPLES / "executors" / "examples_rclpy_executors" / "custom_executor.py",
                               ROS2_EXAMPLES / "actions" / "minimal_action_server"], "p", Path.cwd())
    composed = project["nodes"]["custom_executor"]  # Listener, Talker (imported classes) and Estopper
    assert "name" not in composed
    assert composed["publish"] == {"chatter": "std_msgs/msg/String"}
    assert composed["subscribe"] == {"chatter": "std_msgs/msg/String", "estop": "std_msgs/msg/String"}
    servers = [n for n in project["nodes"].values() if "actions" in n]
    assert len(servers) == 5 and all(n["actions"] == {"fibonacci": "example_interfaces/action/Fibonacci"}
                                     for n in servers)


def test_init_reads_rospy_scripts_and_their_star_imported_types(tmp_path: Path) -> None:
    from hetros.project import ros_template

    project, _ = ros_template([TUTORIALS], "p", tmp_path)
    nodes = project["nodes"]
    assert nodes["talker"]["publish"] == {"chatter": "std_msgs/msg/String"}
    assert nodes["listener"]["subscribe"] == {"chatter": "std_msgs/msg/String"}
    assert nodes["add_two_ints_server"]["services"] == {"add_two_ints": "rospy_tutorials/srv/AddTwoInts"}
    assert nodes["add_two_ints_client"]["clients"] == {"add_two_ints": "rospy_tutorials/srv/AddTwoInts"}
    assert (tmp_path / nodes["talker"]["run"]).resolve() == (TUTORIALS / "001_talker_listener" / "talker.py")


def test_init_leaves_a_placeholder_that_check_refuses_naming_file_and_line(tmp_path: Path) -> None:
    from hetros.project import check, load_project, ros_template

    (tmp_path / "relay.py").write_text(
        "import rclpy\nfrom rclpy.node import Node\nfrom std_msgs.msg import String\n\n\n"
        "class Relay(Node):\n"
        "    def __init__(self):\n"
        "        super().__init__('relay')\n"
        "        topic = sys.argv[1]\n"
        "        self.create_subscription(String, topic, print, rclpy.qos.qos_profile_sensor_data)\n"
        "        self.create_publisher(String, 'out', rclpy.qos.qos_profile_sensor_data)\n\n\n"
        "def main():\n    rclpy.init()\n    rclpy.spin(Relay())\n", encoding="utf-8")
    project, notes = ros_template([tmp_path / "relay.py"], "p", tmp_path)
    assert notes == ["relay.py:10: self.create_subscription(..., topic) names its subscribe endpoint at run time; "
                     "replace the placeholder under nodes.relay.subscribe with the name (hetros check refuses it "
                     "until then)"]
    assert project["topics"] == {"/out": {"reliability": "best_effort", "history": "keep_last", "depth": 5}}
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(project))
    report = check(load_project(tmp_path / "p.yaml"))
    assert len(report.errors) == 1 and "placeholder 'topic at relay.py:10' left by `hetros init`" in report.errors[0]


def test_init_follows_names_through_constructor_arguments_and_attributes(tmp_path: Path) -> None:
    """ros2/demos' quality_of_service_demo shape: main passes a local to a Node subclass, whose __init__
    keeps it in an attribute that another method names its endpoint with."""
    (tmp_path / "qos.py").write_text(
        "import rclpy\nfrom rclpy.node import Node\nfrom std_msgs.msg import String\n\n\n"
        "class Talker(Node):\n"
        "    def __init__(self, topic_name, qos, node_name='talker'):\n"
        "        super().__init__(node_name)\n"
        "        self.topic_name = topic_name\n"
        "        self.pub = self.create_publisher(String, topic_name, qos)\n\n"
        "    def again(self):\n"
        "        return self.create_subscription(String, self.topic_name + '_echo', print, 10)\n\n\n"
        "def main():\n    rclpy.init()\n    topic = 'qos_chatter'\n    Talker(topic, 10)\n", encoding="utf-8")
    project, notes = ros_template([tmp_path / "qos.py"], "p", tmp_path)
    assert notes == []
    node = project["nodes"]["talker"]
    assert node["publish"] == {"qos_chatter": "std_msgs/msg/String"}
    assert node["subscribe"] == {"qos_chatter_echo": "std_msgs/msg/String"}


def test_init_names_a_topic_by_its_parameter_and_says_so(tmp_path: Path) -> None:
    (tmp_path / "relay.py").write_text(
        "import rclpy\nfrom rclpy.node import Node\nfrom std_msgs.msg import String\n\n\n"
        "class Relay(Node):\n"
        "    def __init__(self):\n"
        "        super().__init__('relay')\n"
        "        topic = self.declare_parameter('topic', 'in').value\n"
        "        self.create_subscription(String, topic, print, 10)\n\n\n"
        "def main():\n    rclpy.init()\n    rclpy.spin(Relay())\n", encoding="utf-8")
    project, notes = ros_template([tmp_path / "relay.py"], "p", tmp_path)
    assert project["nodes"]["relay"]["subscribe"] == {"in": "std_msgs/msg/String"}
    assert notes == ["relay.py:10: the subscribe endpoint is named by parameter 'topic': written as 'in', its value "
                     "here; a project that sets the parameter to another name must rename the endpoint under "
                     "nodes.relay.subscribe too"]


def test_init_reads_topics_named_through_constants(tmp_path: Path) -> None:
    """A topic in a module constant, a function's local, or a + of those is read as the string it is; a name
    bound to anything else stays a placeholder."""
    from hetros.project import ros_template

    (tmp_path / "relay.py").write_text(
        "import rclpy\nfrom std_msgs.msg import String\n\nPREFIX = 'robot'\nSTATUS = 'status'\n\n\n"
        "def main(args=None):\n"
        "    rclpy.init(args=args)\n"
        "    node = rclpy.create_node('relay')\n"
        "    topic = 'chatter'\n"
        "    node.create_subscription(String, topic, print, 10)\n"
        "    node.create_publisher(String, PREFIX + '/' + STATUS, 10)\n"
        "    for name in ('a', 'b'):\n"
        "        node.create_publisher(String, name, 10)\n"
        "    rclpy.spin(node)\n", encoding="utf-8")
    project, notes = ros_template([tmp_path / "relay.py"], "p", tmp_path)
    node = project["nodes"]["relay"]
    assert node["subscribe"] == {"chatter": "std_msgs/msg/String"}
    assert "robot/status" in node["publish"] and len(node["publish"]) == 2
    assert notes == ["relay.py:15: node.create_publisher(..., name) names its publish endpoint at run time; replace "
                     "the placeholder under nodes.relay.publish with the name (hetros check refuses it until then)"]


def test_init_skips_tests_and_symlinks_and_adds_the_packages_own_interfaces(tmp_path: Path) -> None:
    """A package's test/ scripts are no nodes, a symlink to a script is not a second node, and a package's own
    msg/ is in the project's messages:."""
    import shutil

    from hetros.project import ros_template

    package = tmp_path / "pkg"
    shutil.copytree(TUTORIALS / "001_talker_listener", package / "scripts", symlinks=True)
    (package / "package.xml").write_text("<package><name>pkg</name></package>\n")
    (package / "msg").mkdir()
    (package / "msg" / "Count.msg").write_text("int32 count\n")
    (package / "test").mkdir()
    shutil.copy(TUTORIALS / "001_talker_listener" / "talker.py", package / "test" / "talker_test.py")
    (package / "scripts" / "talker_link.py").symlink_to(package / "scripts" / "talker.py")
    project, _ = ros_template([package], "p", tmp_path)
    assert sorted(n["run"] for n in project["nodes"].values()) == ["pkg/scripts/listener.py", "pkg/scripts/talker.py"]
    assert project["messages"] == ["pkg"]


def test_init_writes_into_a_folder_it_makes(tmp_path: Path) -> None:
    """`-o sub/project.yaml` where sub/ does not exist yet: made, not a traceback."""
    from hetros.cli import main

    (tmp_path / "nodes.py").write_text("from hetros import Node\nfrom hetros.interfaces.std_msgs.msg import String\n"
                                       "\n\ndef talker(node: Node) -> None:\n"
                                       "    node.create_publisher(String, '/chatter')\n", encoding="utf-8")
    out = tmp_path / "sub" / "deeper" / "project.yaml"
    assert main(["init", str(tmp_path / "nodes.py"), "-o", str(out)]) == 0
    written = yaml.safe_load(out.read_text())
    assert "talker" in written["nodes"]
    assert written["python_path"] == ["../.."]
    # it checks from where it was written: the module is found through python_path:, not PYTHONPATH
    assert main(["check", str(out)]) == 0


def test_python_path_must_name_folders(tmp_path: Path) -> None:
    from hetros.project import check, load_project

    (tmp_path / "project.yaml").write_text("name: p\npython_path: [src, missing]\nnodes:\n"
                                          "  a: {run: 'nodes:a'}\n", encoding="utf-8")
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "nodes.py").write_text("def a(node):\n    pass\n", encoding="utf-8")
    report = check(load_project(tmp_path / "project.yaml"))
    assert [e for e in report.errors if "python_path" in e] == [
        f"{tmp_path / 'project.yaml'}:2: python_path.1: {str(tmp_path / 'missing')!r} is not a folder; python_path "
        "lists the folders node modules are imported from, relative to the project file"]
    assert not any("found neither" in e for e in report.errors), report.errors


def test_a_file_without_main_gives_each_ros_function_a_node(tmp_path: Path) -> None:
    """Two rclpy functions in one file and nothing that runs on its own: two nodes (module:function), not one
    script node that would do nothing. With a __main__ guard the file stays a script, as ROS runs it."""
    body = ("import rclpy\nfrom std_msgs.msg import String\n\n\n"
            "def talker():\n    rclpy.init()\n    node = rclpy.create_node('talker')\n"
            "    node.create_publisher(String, 'chatter', 10)\n\n\n"
            "def listener():\n    rclpy.init()\n    node = rclpy.create_node('listener')\n"
            "    node.create_subscription(String, 'chatter', print, 10)\n\n\n"
            "def helper(x):\n    return x + 1\n")
    (tmp_path / "pair.py").write_text(body, encoding="utf-8")
    project, _ = ros_template([tmp_path / "pair.py"], "p", tmp_path)
    assert {k: n["run"] for k, n in project["nodes"].items()} == {"talker": "pair:talker", "listener": "pair:listener"}
    (tmp_path / "script.py").write_text(body + "\n\nif __name__ == '__main__':\n    talker()\n", encoding="utf-8")
    project, _ = ros_template([tmp_path / "script.py"], "p", tmp_path)
    assert [n["run"] for n in project["nodes"].values()] == ["script.py"]


def test_a_node_with_the_logger_service_serves_its_levels_under_its_name(tmp_path: Path) -> None:
    """rclpy's ``enable_logger_service=True`` gives the node two services, which the project must declare."""
    (tmp_path / "levels.py").write_text(
        "import rclpy\nfrom rclpy.node import Node\n\n\nclass Quiet(Node):\n    def __init__(self):\n"
        "        super().__init__('quiet', enable_logger_service=True)\n\n\n"
        "def main():\n    rclpy.init()\n    rclpy.spin(Quiet())\n", encoding="utf-8")
    project, _ = ros_template([tmp_path / "levels.py"], "p", tmp_path)
    assert project["nodes"]["quiet"]["services"] == {
        "quiet/get_logger_levels": "rcl_interfaces/srv/GetLoggerLevels",
        "quiet/set_logger_levels": "rcl_interfaces/srv/SetLoggerLevels"}


def test_init_writes_a_topics_qos_only_where_its_code_fixes_it_alike(tmp_path: Path) -> None:
    """A QoS computed at run time (in a variable, a policy from the arguments) is not written; nodes that ask
    one topic different QoS get none for it, and a note says so."""
    from hetros.project import ros_template

    package = tmp_path / "pkg"
    (package / "pkg").mkdir(parents=True)
    (package / "package.xml").write_text("<package><name>pkg</name></package>\n")
    (package / "pkg" / "__init__.py").write_text("")
    (package / "pkg" / "nodes.py").write_text(
        "import rclpy\nfrom rclpy.qos import QoSProfile, ReliabilityPolicy\nfrom std_msgs.msg import String\n\n\n"
        "def a():\n    node = rclpy.create_node('a')\n    node.create_publisher(String, 'x', 10)\n"
        "    node.create_publisher(String, 'same', 10)\n\n\n"
        "def b():\n    node = rclpy.create_node('b')\n    node.create_subscription(String, 'x', print, "
        "QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT))\n"
        "    node.create_subscription(String, 'same', print, 10)\n\n\n"
        "def c(reliable):\n    node = rclpy.create_node('c')\n    node.create_publisher(String, 'computed', "
        "QoSProfile(depth=10, reliability=reliable))\n")
    (package / "setup.py").write_text(
        "from setuptools import setup\nsetup(name='pkg', entry_points={'console_scripts': ['a = pkg.nodes:a', "
        "'b = pkg.nodes:b', 'c = pkg.nodes:c']})\n")
    project, notes = ros_template([package], "p", tmp_path)
    assert project["topics"] == {"/same": {"history": "keep_last", "depth": 10}}
    assert any(note.startswith("topic /x: its nodes ask different QoS in code") for note in notes), notes


def test_init_finds_a_managed_nodes_endpoints() -> None:
    """ros2/demos's lifecycle_py: a LifecycleNode whose publisher is made in on_configure."""
    from hetros.project import ros_template

    package = Path(__file__).resolve().parents[1] / "data" / "ros2_demos" / "lifecycle_py"
    project, _ = ros_template([package], "p", package)
    assert project["nodes"]["lc_talker"]["lifecycle"] == "unconfigured"
    assert project["nodes"]["lc_talker"]["publish"] == {"lifecycle_chatter": "std_msgs/msg/String"}
