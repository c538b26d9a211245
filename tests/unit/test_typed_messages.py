"""Typed messages for users: the stubs of hetros.interfaces are fresh and mypy reads them."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from hetros.msg._stubs import shipped_stubs, user_stubs

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_the_shipped_stubs_are_fresh() -> None:
    """Generated code is never edited: regenerate with `hetros msg stubs --shipped`."""
    stale = [str(path) for path, text in shipped_stubs().items()
             if not path.exists() or path.read_text(encoding="utf-8") != text]
    assert not stale, "stale stubs (run `hetros msg stubs --shipped`): " + ", ".join(stale)


USER_FILE = '''
from hetros import Node
from hetros.interfaces.lane_msgs.msg import LaneCentre
from hetros.interfaces.sensor_msgs.msg import Image
from hetros.interfaces.sorter_msgs.action import Sort
from hetros.interfaces.std_srvs.srv import SetBool


def node(node: Node) -> None:
    def on_image(image: Image) -> None:
        seconds: int = image.header.stamp.sec
        node.log.info("%d x %d at %d", image.height, image.width, seconds)

    def answer(request: SetBool.Request) -> SetBool.Response:
        return SetBool.Response(success=request.data, message="ok")

    node.create_subscription(Image, "/image", on_image)
    node.create_service(SetBool, "/set", answer)
    publisher = node.create_publisher(LaneCentre, "/lane")
    publisher.publish(LaneCentre(centre_px=0.5))
    goal: Sort.Goal = Sort.Goal(unsorted=[3, 1, 2])
    node.log.info("%s", goal)
'''


def _mypy(tmp_path: Path, source: str) -> subprocess.CompletedProcess[str]:
    user_stubs([EXAMPLES / "lane_following" / "msg", EXAMPLES / "sort_action" / "msg"], tmp_path / "typings")
    (tmp_path / "user.py").write_text(textwrap.dedent(source), encoding="utf-8")
    env = {**os.environ, "MYPYPATH": str(tmp_path / "typings")}
    return subprocess.run([sys.executable, "-m", "mypy", "--strict", "--no-incremental", "user.py"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=300)


@pytest.mark.slow
def test_mypy_strict_reads_shipped_and_user_built_types(tmp_path: Path) -> None:
    done = _mypy(tmp_path, USER_FILE)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.slow
def test_mypy_catches_a_field_that_does_not_exist_and_a_wrong_field_type(tmp_path: Path) -> None:
    done = _mypy(tmp_path, USER_FILE + '''

def wrong(image: Image) -> str:
    image.heigth
    return image.width
''')
    assert done.returncode == 1
    assert '"Image" has no attribute "heigth"' in done.stdout
    assert 'Incompatible return value type (got "int", expected "str")' in done.stdout
