"""message_filters in running graphs: its own Cache test (which makes a node and a Subscriber) run as a
node of a launch, and an rclpy node synchronising a camera image with its camera_info published by
another process (message_filters.Subscriber, ApproximateTimeSynchronizer), as a real package does."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import yaml

from tests.support.cli import hetros_in

DATA = Path(__file__).resolve().parents[1] / "data"


def test_message_filters_own_cache_test_passes_as_a_node(tmp_path: Path) -> None:
    (tmp_path / "runner.py").write_text(
        "import sys\n\nimport pytest\n\n\ndef main():\n"
        "    sys.exit(int(pytest.main(['-q', '-p', 'no:cacheprovider', sys.argv[1]])))\n")
    project = {"name": "mftest", "nodes": {"my_node": {
        "run": "runner:main", "namespace": "/my_ns",
        "args": [str(DATA / "upstream_message_filters" / "test_message_filters_cache.py")],
        "subscribe": {"/empty": "std_msgs/msg/String"}}}}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project))
    done = hetros_in("launch", str(tmp_path / "project.yaml"), cwd=tmp_path, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "2 passed" in done.stdout + done.stderr


def test_an_image_and_its_camera_info_are_paired_across_processes(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""\
        import message_filters
        import rclpy
        from rclpy.node import Node
        from sensor_msgs.msg import CameraInfo, Image


        class Camera(Node):
            def __init__(self):
                super().__init__('camera')
                self.image = self.create_publisher(Image, 'image', 10)
                self.info = self.create_publisher(CameraInfo, 'camera_info', 10)
                self.count = 0
                self.create_timer(0.05, self.tick)

            def tick(self):
                if self.count == 20:
                    return
                stamp = self.get_clock().now().to_msg()
                image = Image(height=2, width=2, encoding='mono8', step=2, data=[self.count] * 4)
                image.header.stamp = stamp
                info = CameraInfo(height=2, width=2)
                info.header.stamp = stamp
                if self.count % 5 != 3:  # every fifth image goes without its info
                    self.info.publish(info)
                self.image.publish(image)
                self.count += 1


        class Pairer(Node):
            def __init__(self):
                super().__init__('pairer')
                image = message_filters.Subscriber(self, Image, 'image')
                info = message_filters.Subscriber(self, CameraInfo, 'camera_info')
                sync = message_filters.ApproximateTimeSynchronizer([image, info], 10, 0.01)
                sync.registerCallback(self.paired, 'tag')

            def paired(self, image, info, tag):
                same = image.header.stamp == info.header.stamp
                self.get_logger().info(f'paired image {image.data[0]} same stamp {same} {tag}')


        def camera():
            with rclpy.init():
                rclpy.spin(Camera())


        def pairer():
            with rclpy.init():
                rclpy.spin(Pairer())
        """))
    project = {"name": "pairing", "targets": {"c": {"kind": "process"}, "p": {"kind": "process"}}, "nodes": {
        "camera": {"run": "nodes:camera", "target": "c",
                   "publish": {"/image": "sensor_msgs/msg/Image", "/camera_info": "sensor_msgs/msg/CameraInfo"}},
        "pairer": {"run": "nodes:pairer", "target": "p",
                   "subscribe": {"/image": "sensor_msgs/msg/Image", "/camera_info": "sensor_msgs/msg/CameraInfo"}}}}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project))
    done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "3", cwd=tmp_path, timeout=120)
    assert done.returncode == 0, done.stderr
    paired = [int(n) for n in re.findall(r"\[pairer\]: paired image (\d+) same stamp True tag$", done.stderr,
                                         re.MULTILINE)]
    assert paired == [n for n in range(20) if n % 5 != 3], done.stderr
