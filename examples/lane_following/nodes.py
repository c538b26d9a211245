"""The lane-following vehicle of fpgaDDS (Fig. 6): camera -> compensation -> (A) -> blur -> (B) ->
projection -> lane following -> lane control, with red and green traffic-light detection on A
(topics E and F). Chain alpha (compensation -> control) latency is measured per frame from the
camera's timestamp to the command.
"""

import json
from pathlib import Path

import numpy as np
import vision

from hetros import Node, Time
from hetros.interfaces.geometry_msgs.msg import TwistStamped
from hetros.interfaces.lane_msgs.msg import LaneCentre, LightState
from hetros.interfaces.sensor_msgs.msg import Image
from hetros.interfaces.std_msgs.msg import Header


def to_image(pixels: np.ndarray, header: Header, encoding: str) -> Image:
    channels = 1 if pixels.ndim == 2 else pixels.shape[2]
    return Image(header=header, height=pixels.shape[0], width=pixels.shape[1], encoding=encoding,
                 step=pixels.shape[1] * channels, data=pixels.reshape(-1))


def pixels(msg: Image) -> np.ndarray:
    shape = (msg.height, msg.width) if msg.encoding == "mono8" else (msg.height, msg.width, 3)
    return msg.data.reshape(shape)


def camera(node: Node) -> None:
    pub = node.create_publisher(Image, "/image_raw")
    truth = node.create_publisher(LaneCentre, "/ground_truth")
    for frame in node.rate(node.get_parameter("hz", 10.0)):
        if frame >= node.get_parameter("frames", 45):
            node.spin()
            return
        img, centre = vision.render(frame)
        msg = pub.loan(data=img.size)
        msg.data[:] = img.reshape(-1)
        msg.height, msg.width, msg.encoding, msg.step = img.shape[0], img.shape[1], "rgb8", img.shape[1] * 3
        msg.header.frame_id = f"frame{frame}"
        msg.header.stamp = node.get_clock().now().to_msg()
        header = msg.header.copy()
        pub.publish(msg)
        truth.publish(LaneCentre(header=header, found=True, centre_px=centre))


def stage(node: Node, source: str, target: str, work, encoding: str = "rgb8") -> None:  # type: ignore[no-untyped-def]
    pub = node.create_publisher(Image, target)
    for msg in node.create_subscription(Image, source):
        pub.publish(to_image(work(pixels(msg)), msg.header, encoding))


def compensation(node: Node) -> None:
    stage(node, "/image_raw", "/image_comp", vision.compensate())


def gaussian_blur(node: Node) -> None:
    stage(node, "/image_comp", "/image_blur", vision.blur)


def projection(node: Node) -> None:
    stage(node, "/image_blur", "/image_bev", vision.project, "mono8")


def lane_following(node: Node) -> None:
    pub = node.create_publisher(LaneCentre, "/lane_centre")
    for msg in node.create_subscription(Image, "/image_bev"):
        found, centre, left, right = vision.find_lane(pixels(msg))
        pub.publish(LaneCentre(header=msg.header, found=found, centre_px=centre, left_px=left, right_px=right))


def light_detection(node: Node, colour: str) -> None:
    pub = node.create_publisher(LightState, f"/light_{colour}")
    for msg in node.create_subscription(Image, "/image_comp"):
        count = vision.light_pixels(pixels(msg), colour)
        pub.publish(LightState(header=msg.header, on=count > 150, pixels=count))


def red_light(node: Node) -> None:
    light_detection(node, "red")


def green_light(node: Node) -> None:
    light_detection(node, "green")


def lane_control(node: Node) -> None:
    """Steer to the lane centre; stop on red, go again on green.

    The light verdicts are buffered subscriptions; each command waits for both verdicts of
    its own frame (matched by frame id), so the decision never depends on which stage of
    the chain happened to be faster.
    """
    pub = node.create_publisher(TwistStamped, "/cmd_vel")
    red = node.create_subscription(LightState, "/light_red")
    green = node.create_subscription(LightState, "/light_green")
    stopped = False
    for lane in node.create_subscription(LaneCentre, "/lane_centre"):
        for light, value in ((red, True), (green, False)):
            while True:
                state = light.take(timeout=10.0)
                if state.on:
                    stopped = value
                if state.header.frame_id == lane.header.frame_id:
                    break
        cmd = TwistStamped(header=lane.header)
        cmd.twist.linear.x = 0.0 if stopped else 1.0
        cmd.twist.angular.z = -0.01 * (lane.centre_px - vision.BEV_W / 2) if lane.found else 0.0
        pub.publish(cmd)


def monitor(node: Node) -> None:
    """Checks the chain against the renderer's ground truth, reports latency, writes PNGs."""
    commands = node.create_subscription(TwistStamped, "/cmd_vel")
    centres = node.create_subscription(LaneCentre, "/lane_centre")
    truths = node.create_subscription(LaneCentre, "/ground_truth")
    frames = node.get_parameter("frames", 45)
    truth, seen, latencies, speeds, errors = {}, {}, [], {}, []
    for _ in range(frames):
        cmd = commands.take(timeout=30.0)
        latencies.append((node.get_clock().now() - Time.from_msg(cmd.header.stamp)).nanoseconds / 1e6)
        frame = int(cmd.header.frame_id.removeprefix("frame"))
        speeds[frame] = cmd.twist.linear.x
        while (t := truths.try_take()) is not None:
            truth[t.header.frame_id] = t.centre_px
        while (c := centres.try_take()) is not None:
            seen[c.header.frame_id] = c.centre_px
    for frame_id, centre in seen.items():
        errors.append(abs(centre - truth[frame_id]))
    stopped = sorted(f for f, v in speeds.items() if v == 0.0)
    lat = np.array(latencies)
    node.log.info("chain alpha latency %.1f ± %.1f ms over %d frames; centre error max %.2f px; "
                  "stopped in frames %s", lat.mean(), lat.std(), lat.size, max(errors), stopped)
    out = node.get_parameter("out", "")
    if out:
        write_pngs(Path(out), lat)
        node.log.info("wrote %s and %s", Path(out) / "latency.png", Path(out) / "frame.png")
    if out:
        (Path(out) / "summary.json").write_text(json.dumps({"latency_ms": latencies, "stopped": stopped,
                                                            "centres": dict(sorted(seen.items()))}))


def write_pngs(out: Path, latencies: np.ndarray) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.hist(latencies, bins=20)
    ax.set_xlabel("chain alpha latency (ms)")
    ax.set_ylabel("frames")
    fig.tight_layout()
    fig.savefig(out / "latency.png", dpi=100)
    plt.close(fig)
    frame = 25
    img, truth = vision.render(frame)
    compensate = vision.compensate()
    compensate(vision.render(frame - 1)[0])  # the stretch comes from the frame before
    bev = vision.project(vision.blur(compensate(img)))
    _found, centre, left, right = vision.find_lane(bev)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    axes[0].imshow(img)
    axes[0].set_title(f"camera frame {frame}: light {'red' if vision.light_is_red(frame) else 'green'}")
    axes[1].imshow(bev, cmap="gray")
    for x, colour in ((left, "tab:blue"), (right, "tab:blue"), (centre, "tab:red"), (truth, "tab:green")):
        axes[1].axvline(x, color=colour, lw=1)
    axes[1].axhline(vision.NEAR_ROW, color="yellow", lw=0.5)
    axes[1].set_title("bird's-eye view: stripes (blue), centre (red), truth (green)")
    fig.tight_layout()
    fig.savefig(out / "frame.png", dpi=100)
    plt.close(fig)
