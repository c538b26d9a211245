"""The rendered standard definitions (``hetros/msg/standard_types.json``) are what rosbags and msg/packages say,
and a process that only moves messages never builds rosbags' type system."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from hetros.msg import _standard
from hetros.msg._registry import TypeRegistry


def test_the_rendered_module_is_fresh() -> None:
    assert _standard.TARGET.read_text(encoding="utf-8") == _standard.render(), (
        "src/hetros/msg/standard_types.json is stale: run `python -m hetros.msg._standard`")


def test_the_rendered_definitions_equal_rosbags_and_the_shipped_packages() -> None:
    from rosbags.typesys import Stores, get_typestore

    assert _standard.load().standard == dict(get_typestore(Stores.ROS2_JAZZY).fielddefs)
    lazy = TypeRegistry()
    assert "example_interfaces/srv/AddTwoInts_Request" in lazy.fielddefs
    assert lazy.sources["action_msgs/srv/CancelGoal_Request"].endswith("packages/action_msgs/srv/CancelGoal.srv")
    assert lazy.store.fielddefs["example_interfaces/srv/AddTwoInts_Request"] == \
        lazy.fielddefs["example_interfaces/srv/AddTwoInts_Request"]


def test_the_store_built_late_knows_every_type_and_class_registered_before() -> None:
    types = TypeRegistry()
    cls = types.get("std_msgs/msg/String")
    assert types._store is None
    message = cls(data="late")
    assert types.deserialize(types.serialize(message), "std_msgs/msg/String").data == "late"
    assert types.store.types["std_msgs/msg/String"] is cls


def test_moving_messages_loads_neither_rosbags_type_system_nor_openssl() -> None:
    code = textwrap.dedent('''
        import sys
        from hetros.interfaces.std_msgs.msg import String
        from hetros.msg import registry
        codec = registry().codec("std_msgs/msg/String")
        message = String(data="hello")
        buffer = memoryview(bytearray(codec.size(message)))
        codec.encode(message, buffer)
        assert codec.decode(buffer).data == "hello"
        print(sorted(m for m in sys.modules if m.startswith("rosbags.typesys") or m in ("hashlib", "_hashlib")))
    ''')
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
