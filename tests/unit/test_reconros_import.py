"""`hetros import reconros`: every construct of ReconROS's configuration files is mapped, or refused
naming file:line (ReconOS's own resources are named in the notes)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from hetros import ProjectError
from hetros.project import import_reconros


def _cfg(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "build.cfg"
    path.write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return path


def test_services_and_actions_both_ways_and_both_spellings(tmp_path: Path) -> None:
    project, notes = import_reconros(_cfg(tmp_path, """
        [ResourceGroup@Client]
        Result = mbox,128
        sort_srv = rossrvmsg, sorter_msgs ,srv ,Sort
        node_1 = rosnode, "sorterclient"
        srv = rossrvc, node_1, sort_srv, "sorter", 10000
        [ResourceGroup@Actions]
        sort_action= rosactionmsg, sorter_msgs ,action ,Sort
        node_1 = rosnode, "actor"
        a = rosacts, node_1, sort_action, "sort_a", 10000
        b = rosactc, node_1, sort_action, "sort_b", 10000
        c = rosactions, node_1, sort_action, "sort_c", 10000
        d = rosactionc, node_1, sort_action, "sort_d", 10000
    """))
    assert project["nodes"]["sorterclient"]["clients"] == {"/sorter": "sorter_msgs/srv/Sort"}
    assert project["nodes"]["actor"]["actions"] == {"/sort_a": "sorter_msgs/action/Sort",
                                                    "/sort_c": "sorter_msgs/action/Sort"}
    assert project["nodes"]["actor"]["action_clients"] == {"/sort_b": "sorter_msgs/action/Sort",
                                                           "/sort_d": "sorter_msgs/action/Sort"}
    assert notes == [f"{tmp_path / 'build.cfg'}:2: Result = mbox is ReconOS's own mbox resource between a thread's "
                     "hardware and software halves; hetros nodes talk through topics, so it is not carried over"]


def test_a_ranged_resource_group_is_one_target_per_index_with_percent_replaced(tmp_path: Path) -> None:
    project, _ = import_reconros(_cfg(tmp_path, """
        [ResourceGroup@Control(0:2)]
        cmd = rosmsg, std_msgs, msg, Float64
        node_1 = rosnode, "control_%"
        out = rospub, node_1, cmd, "/joint_%/command"
        [ReconosThread@Control]
        HwSource = hls
        ResourceGroup = Control
    """))
    assert sorted(project["nodes"]) == ["control_0", "control_1", "control_2"]
    assert project["nodes"]["control_1"] == {"run": "nodes:control_1", "target": "control_1",
                                             "hw": "nodes_hw:control_1",
                                             "publish": {"/joint_1/command": "std_msgs/msg/Float64"}}
    assert "%" not in repr(project)


@pytest.mark.parametrize(("text", "message"), [
    ("""
     [ResourceGroup@G]
     node_1 = rosnode, "n"
     [ROSGateway@Gateway1]
     HWTopic = "nicehwtopic"
     """, ":3: [ROSGateway@Gateway1] needs SWTopic, MsgType (a gateway joins HWTopic to SWTopic, both of MsgType)"),
    ("""
     [ResourceGroup@G]
     node_1 = rosnode, "n"
     [ROSGateway@Gateway1]
     HWTopic = "nicehwtopic"
     SWTopic = "/sw"
     MsgType = sensor_msgs/Image
     """, ":3: [ROSGateway@Gateway1] joins hardware topic /nicehwtopic, which no node publishes or subscribes"),
    ("""
     [ResourceGroup@G]
     data = rosmsg, std_msgs, msg, UInt32, 1000
     """, ":2: rosmsg with a sequence length (std_msgs, msg, UInt32, 1000) is ReconROS's preallocated "
          "std_msgs/UInt32 sequence"),
    ("""
     [ResourceGroup@G]
     node_1 = rosnode, "n"
     x = rostimer, node_1, 100
     """, ":3: rostimer is a ReconROS resource hetros does not map"),
])
def test_what_has_no_counterpart_is_refused_with_file_and_line(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(ProjectError) as info:
        import_reconros(_cfg(tmp_path, text))
    assert message in str(info.value)
    assert str(tmp_path / "build.cfg") in str(info.value)


def test_reconros_gateways_and_two_implementations_map_to_one_topic_and_hw(tmp_path: Path) -> None:
    """ReconROS's ros_hwtopic_gateway demo's shape: threads on a hardware topic, a gateway to software."""
    project, notes = import_reconros(_cfg(tmp_path, """
        [General]
        TargetPart = xczu7ev-ffvc1156-2-e
        [ResourceGroup@RThreadb]
        img_input = rosmsg, sensor_msgs ,msg ,Image
        node_1 = rosnode, "filter"
        SubData = rossub, node_1, img_input, "/inputtopic", 10000
        PubData = rospub, node_1, sensor_msgs/Image, "nicehwtopic", hw
        [ResourceGroup@Viewer]
        node_1 = rosnode, "viewer"
        in = rossub, node_1, sensor_msgs/Image, "/topic/gateway", 10000
        [ResourceGroup@Both]
        node_1 = rosnode, "sorter"
        out = rospub, node_1, sensor_msgs/Image, "/sorted"
        [ReconosThread@Threadb]
        HwSource = hls
        ResourceGroup = RThreadb
        [ReconosThread@Sorter]
        HwSource = hls
        SwSource = c
        ResourceGroup = Both
        [ROSGateway@Gateway1]
        Slot = Gateways(0)
        HWTopic = "nicehwtopic"
        SWTopic = "/topic/gateway"
        MsgType = sensor_msgs/Image
    """))
    nodes = project["nodes"]
    assert nodes["filter"]["target"] == "fpga" and nodes["filter"]["hw"] == "nodes_hw:filter"
    assert nodes["filter"]["publish"] == {"/topic/gateway": "sensor_msgs/msg/Image"}
    assert nodes["viewer"]["target"] == "viewer" and "hw" not in nodes["viewer"]
    # HwSource and SwSource: both implementations, the software target kept
    assert nodes["sorter"]["target"] == "both" and nodes["sorter"]["hw"] == "nodes_hw:sorter"
    assert any("[ROSGateway@Gateway1] joins hardware topic /nicehwtopic to software topic /topic/gateway" in n
               for n in notes)
    assert any("sorter gets hw: nodes_hw:<node>" in n and "both implementations" in n for n in notes)
