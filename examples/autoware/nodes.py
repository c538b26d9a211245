"""ROS-lite's Autoware slice (Fig. 11): waypoint_loader -> lane_rule -> lane_select ->
waypoint_filter -> velocity_set -> pure_pursuit -> twist_filter, driving a simulated car.

The car (a kinematic unicycle) publishes its pose at 10 Hz and, in lockstep, applies
the twist command that answers it; it records the lateral error to the route and how
often the chain missed the 100 ms deadline.
"""

import time

import numpy as np

from hetros import Node, QoS, ShutdownError
from hetros.interfaces.autoware_msgs.msg import Lane, LaneArray, Waypoint
from hetros.interfaces.geometry_msgs.msg import PoseStamped, TwistStamped

DT = 0.1
LANE_WIDTH = 3.5
CRUISE = 8.0
LATERAL_ACCEL = 2.0


def centreline(count: int = 220) -> np.ndarray:
    """The route: 1 m apart, gently curving (y = 5 sin(x / 30))."""
    x = np.arange(count, dtype=np.float64)
    return np.stack([x, 5.0 * np.sin(x / 30.0)], axis=1)


def offset(points: np.ndarray, distance: float) -> np.ndarray:
    tangent = np.gradient(points, axis=0)
    normal = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1) / np.linalg.norm(tangent, axis=1)[:, None]
    shifted: np.ndarray = points + distance * normal
    return shifted


def distance_to_route(route: np.ndarray, x: float, y: float) -> float:
    """Distance from (x, y) to the polyline through ``route`` (not just to its vertices)."""
    start, end = route[:-1], route[1:]
    along = end - start
    t = np.clip(((np.array([x, y]) - start) * along).sum(1) / (along**2).sum(1), 0.0, 1.0)
    nearest = start + t[:, None] * along
    return float(np.min(np.hypot(*(nearest - (x, y)).T)))


def lane_message(points: np.ndarray, velocities: np.ndarray, lane_id: int, closest: int = 0) -> Lane:
    headings = np.arctan2(*np.gradient(points, axis=0)[:, ::-1].T) if len(points) > 1 else np.zeros(len(points))
    waypoints = []
    for (x, y), yaw, v in zip(points, headings, velocities, strict=True):
        wp = Waypoint(velocity=float(v))
        wp.pose.position.x, wp.pose.position.y = float(x), float(y)
        wp.pose.orientation.z, wp.pose.orientation.w = float(np.sin(yaw / 2)), float(np.cos(yaw / 2))
        waypoints.append(wp)
    return Lane(lane_id=lane_id, closest=closest, waypoints=waypoints)


def lane_points(lane: Lane) -> tuple[np.ndarray, np.ndarray]:
    points = np.array([[w.pose.position.x, w.pose.position.y] for w in lane.waypoints]).reshape(-1, 2)
    return points, np.array([w.velocity for w in lane.waypoints])


def pose_xy_yaw(msg: PoseStamped) -> tuple[float, float, float]:
    q = msg.pose.orientation
    return msg.pose.position.x, msg.pose.position.y, float(2 * np.arctan2(q.z, q.w))


LATCHED = QoS.latched()


def waypoint_loader(node: Node) -> None:
    pub = node.create_publisher(LaneArray, "/lane_waypoints_array", qos=LATCHED)
    route = centreline()
    speeds = np.full(len(route), CRUISE)
    pub.publish(LaneArray(lanes=[lane_message(route, speeds, 0), lane_message(offset(route, LANE_WIDTH), speeds, 1)]))
    node.spin()


def lane_rule(node: Node) -> None:
    """Traffic rules: slow down where the lane curves, come to a stop at its end."""
    pub = node.create_publisher(LaneArray, "/traffic_waypoints_array", qos=LATCHED)

    def apply(array: LaneArray) -> None:
        lanes = []
        for lane in array.lanes:
            points, speeds = lane_points(lane)
            d1, d2 = np.gradient(points, axis=0), np.gradient(np.gradient(points, axis=0), axis=0)
            curvature = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.linalg.norm(d1, axis=1) ** 3
            limited = np.minimum(speeds, np.sqrt(LATERAL_ACCEL / np.maximum(curvature, 1e-6)))
            to_end = np.arange(len(points))[::-1].astype(np.float64)
            limited = np.minimum(limited, np.sqrt(2 * 1.0 * to_end))
            lanes.append(lane_message(points, limited, lane.lane_id))
        pub.publish(LaneArray(lanes=lanes))

    node.create_subscription(LaneArray, "/lane_waypoints_array", apply, qos=LATCHED)


def lane_select(node: Node) -> None:
    """Follow the lane nearest to the car; cut it at the closest waypoint."""
    pub = node.create_publisher(Lane, "/base_waypoints")
    lanes = node.create_subscription(LaneArray, "/traffic_waypoints_array", qos=LATCHED)
    array = lanes.take(timeout=30.0)
    parsed = [(lane.lane_id, *lane_points(lane)) for lane in array.lanes]

    def on_pose(msg: PoseStamped) -> None:
        x, y, _ = pose_xy_yaw(msg)
        best = min(parsed, key=lambda item: float(np.min(np.hypot(*(item[1] - (x, y)).T))))
        lane_id, points, speeds = best
        closest = int(np.argmin(np.hypot(*(points - (x, y)).T)))
        lane = lane_message(points, speeds, lane_id, closest)
        lane.header = msg.header
        pub.publish(lane)

    node.create_subscription(PoseStamped, "/current_pose", on_pose)


def waypoint_filter(node: Node) -> None:
    """The part of obstacle_avoid that cuts the next 50 waypoints from the closest one."""
    pub = node.create_publisher(Lane, "/safety_waypoints")

    def cut(lane: Lane) -> None:
        out = Lane(header=lane.header, lane_id=lane.lane_id, closest=0,
                   waypoints=list(lane.waypoints[lane.closest:lane.closest + 50]))
        pub.publish(out)

    node.create_subscription(Lane, "/base_waypoints", cut)


def velocity_set(node: Node) -> None:
    """Final velocities: no faster than a comfortable deceleration allows before a slower point."""
    pub = node.create_publisher(Lane, "/final_waypoints")

    def plan(lane: Lane) -> None:
        points, speeds = lane_points(lane)
        for i in range(len(speeds) - 2, -1, -1):
            step = float(np.hypot(*(points[i + 1] - points[i])))
            speeds[i] = min(speeds[i], np.sqrt(speeds[i + 1] ** 2 + 2 * 1.5 * step))
        out = lane_message(points, speeds, lane.lane_id)
        out.header = lane.header
        pub.publish(out)

    node.create_subscription(Lane, "/safety_waypoints", plan)


def pure_pursuit(node: Node) -> None:
    """Steers for the pose of the cycle its waypoints were cut for (the lane's header is that pose's), as
    message_filters would pair them: the newest pose instead made the trajectory depend on which of the two
    topics' messages a busy machine delivered first."""
    pub = node.create_publisher(TwistStamped, "/twist_raw")
    poses = node.create_subscription(PoseStamped, "/current_pose")  # taken in steer, up to the lane's own
    seen: dict[str, tuple[float, float, float]] = {}

    def steer(lane: Lane) -> None:
        try:
            while lane.header.frame_id not in seen:
                msg = poses.take(timeout=5.0)
                seen[msg.header.frame_id] = pose_xy_yaw(msg)
        except ShutdownError:  # the launch ended while this lane waited for its pose
            return
        x, y, yaw = seen.pop(lane.header.frame_id)
        for older in list(seen)[:-16]:  # poses whose lanes never came (the first ones, a dropped cycle)
            del seen[older]
        points, speeds = lane_points(lane)
        twist = TwistStamped(header=lane.header)
        if len(points):
            speed = float(speeds[0])
            lookahead = max(3.0, 0.5 * speed)
            distances = np.hypot(*(points - (x, y)).T)
            ahead = np.flatnonzero(distances >= lookahead)
            target = points[ahead[0]] if ahead.size else points[-1]
            dx, dy = target - (x, y)
            local_y = -np.sin(yaw) * dx + np.cos(yaw) * dy
            curvature = 2.0 * local_y / max(float(np.hypot(dx, dy)) ** 2, 1e-6)
            twist.twist.linear.x = speed
            twist.twist.angular.z = speed * curvature
        pub.publish(twist)

    node.create_subscription(Lane, "/final_waypoints", steer)


def twist_filter(node: Node) -> None:
    """Safety limits: lateral acceleration and yaw rate."""
    pub = node.create_publisher(TwistStamped, "/twist_cmd")

    def limit(msg: TwistStamped) -> None:
        out = TwistStamped(header=msg.header)
        v = msg.twist.linear.x
        omega = msg.twist.angular.z
        bound = min(LATERAL_ACCEL * 1.5 / max(abs(v), 0.1), 1.0)
        out.twist.linear.x = v
        out.twist.angular.z = float(np.clip(omega, -bound, bound))
        pub.publish(out)

    node.create_subscription(TwistStamped, "/twist_raw", limit)


def vehicle(node: Node) -> None:
    """The simulated car: publish the pose, apply the answering command, 100 ms deadline."""
    pose_pub = node.create_publisher(PoseStamped, "/current_pose")
    commands = node.create_subscription(TwistStamped, "/twist_cmd")
    route = centreline()
    x, y, yaw = 0.0, 0.8, 0.1
    errors, misses, latencies = [], 0, []
    for step in node.rate(node.get_parameter("hz", 10.0)):
        msg = PoseStamped()
        msg.header.frame_id = f"cycle{step}"
        msg.pose.position.x, msg.pose.position.y = x, y
        msg.pose.orientation.z, msg.pose.orientation.w = float(np.sin(yaw / 2)), float(np.cos(yaw / 2))
        sent = time.monotonic()
        pose_pub.publish(msg)
        try:
            while True:
                command = commands.take(timeout=5.0)
                if command.header.frame_id == msg.header.frame_id:
                    break
        except ShutdownError:  # the launch ended (--duration) while this cycle waited: report what drove
            break
        latency = time.monotonic() - sent
        latencies.append(latency * 1000.0)
        misses += latency > 0.1
        v, omega = command.twist.linear.x, command.twist.angular.z
        x, y, yaw = x + v * np.cos(yaw) * DT, y + v * np.sin(yaw) * DT, yaw + omega * DT
        errors.append(distance_to_route(route, x, y))
        if v < 0.05 and step > 20:
            break
    node.log.info("drove to x=%.1f m in %d cycles; lateral error mean %.3f m, max %.3f m, max after 5 s %.3f m; "
                  "chain latency %.1f ± %.1f ms; %d deadline misses (100 ms)",
                  x, len(errors), float(np.mean(errors)), float(np.max(errors)),
                  float(np.max(errors[50:], initial=0.0)), float(np.mean(latencies)), float(np.std(latencies)), misses)
