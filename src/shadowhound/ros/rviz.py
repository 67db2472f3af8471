"""What RViz shows of a mission: the planned path (nav_msgs/Path on `planned_path`) and the
known objects (visualization_msgs/MarkerArray on `known_objects`), in the odometry frame.

The path is the one the governor checked before the mission moved (the `plan_ready` event's
`path`): every leg the robot will walk, around obstacles when the map demanded it. Objects are
the robot's map's and its detections' (`robot_objects`), republished when they change. Both
topics are transient-local (depth 1), so an RViz started later still gets the last ones.

The conversion helpers are pure (no rclpy) and tested without ROS; `RvizPublisher` is the
node-side part (imports the message packages when built).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .. import events as ev
from ..skills.context import robot_objects
from ..state import Pose2D
from ..world.objects import KnownObject

PATH_TOPIC = "planned_path"
OBJECTS_TOPIC = "known_objects"
DEFAULT_FRAME = "odom"
OBJECT_HEIGHT = 0.5  # metres; the map is 2D, a marker needs some height to be seen
OBJECTS_NS = "shadowhound/objects"
LABELS_NS = "shadowhound/labels"


def path_poses(points: Sequence[tuple[float, float]]) -> list[Pose2D]:
    """Poses along a polyline, each facing along the leg it starts (the last one, the leg it
    ends); repeated points are dropped. One point is a pose facing +x."""
    kept: list[tuple[float, float]] = []
    for p in points:
        if not kept or math.dist(kept[-1], p) > 1e-9:
            kept.append((float(p[0]), float(p[1])))
    poses: list[Pose2D] = []
    yaw = 0.0
    for i, (x, y) in enumerate(kept):
        if i + 1 < len(kept):
            nx, ny = kept[i + 1]
            yaw = math.atan2(ny - y, nx - x)
        poses.append(Pose2D(x, y, yaw))
    return poses


@dataclass(frozen=True)
class MarkerSpec:
    """One visualization_msgs/Marker, without ROS: a cylinder for an object, text for its name."""

    ns: str
    id: int
    kind: str  # "cylinder" or "text"
    x: float
    y: float
    z: float
    scale: tuple[float, float, float]
    rgba: tuple[float, float, float, float]
    text: str = ""


def object_markers(objects: Sequence[KnownObject]) -> list[MarkerSpec]:
    """A cylinder (its footprint, more opaque the surer) and a name label per object. Ids are
    positions in the list: the array is sent after a DELETEALL, so none are left over."""
    specs: list[MarkerSpec] = []
    for i, o in enumerate(objects):
        diameter = max(0.05, 2 * o.radius)
        alpha = 0.35 + 0.6 * min(1.0, max(0.0, o.confidence))
        specs.append(
            MarkerSpec(
                OBJECTS_NS,
                i,
                "cylinder",
                o.x,
                o.y,
                OBJECT_HEIGHT / 2,
                (diameter, diameter, OBJECT_HEIGHT),
                (0.9, 0.49, 0.13, alpha),
            )
        )
        specs.append(
            MarkerSpec(
                LABELS_NS,
                i,
                "text",
                o.x,
                o.y,
                OBJECT_HEIGHT + 0.2,
                (0.0, 0.0, 0.2),
                (1.0, 1.0, 1.0, 1.0),
                o.name,
            )
        )
    return specs


def yaw_quaternion(yaw: float) -> tuple[float, float]:
    """(z, w) of the quaternion for a rotation of `yaw` about z."""
    return math.sin(yaw / 2), math.cos(yaw / 2)


# -- messages (need nav_msgs, geometry_msgs, visualization_msgs) ---------------------------


def path_message(poses: Sequence[Pose2D], frame_id: str, stamp: Any) -> Any:
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path

    msg = Path()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    for p in poses:
        pose = PoseStamped()
        pose.header = msg.header
        pose.pose.position.x, pose.pose.position.y = p.x, p.y
        pose.pose.orientation.z, pose.pose.orientation.w = yaw_quaternion(p.yaw)
        msg.poses.append(pose)
    return msg


def marker_array(specs: Sequence[MarkerSpec], frame_id: str, stamp: Any) -> Any:
    from visualization_msgs.msg import Marker, MarkerArray

    clear = Marker()
    clear.header.frame_id = frame_id
    clear.header.stamp = stamp
    clear.action = Marker.DELETEALL
    msg = MarkerArray(markers=[clear])
    for s in specs:
        m = Marker()
        m.header = clear.header
        m.ns, m.id = s.ns, s.id
        m.type = Marker.CYLINDER if s.kind == "cylinder" else Marker.TEXT_VIEW_FACING
        m.action = Marker.ADD
        m.pose.position.x, m.pose.position.y, m.pose.position.z = s.x, s.y, s.z
        m.pose.orientation.w = 1.0
        m.scale.x, m.scale.y, m.scale.z = s.scale
        m.color.r, m.color.g, m.color.b, m.color.a = s.rgba
        m.text = s.text
        msg.markers.append(m)
    return msg


class RvizPublisher:
    """Publishes each mission's planned path and the known objects for `agent` on `node`."""

    def __init__(
        self, node: Any, agent: Any, *, frame_id: str = DEFAULT_FRAME, objects_period: float = 1.0
    ) -> None:
        from nav_msgs.msg import Path
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        latched = QoSProfile(
            depth=1,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
        self._node, self._agent, self.frame_id = node, agent, frame_id
        self._path_pub = node.create_publisher(Path, PATH_TOPIC, latched)
        self._lock = threading.Lock()
        self._objects: tuple[KnownObject, ...] | None = None
        self._unsubscribe = agent.add_listener(self._on_event)
        self._timer: Any = None
        try:
            from visualization_msgs.msg import MarkerArray
        except ImportError:  # an install from before the package was in the ROS list
            node.get_logger().warning(
                f"visualization_msgs is not installed: no {OBJECTS_TOPIC} markers for RViz "
                "(pip install ros-jazzy-visualization-msgs, or run scripts/build_ros.sh)"
            )
            return
        self._objects_pub = node.create_publisher(MarkerArray, OBJECTS_TOPIC, latched)
        self._timer = node.create_timer(objects_period, self.publish_objects)

    def _on_event(self, event: ev.MissionEvent) -> None:
        if event.kind == ev.PLAN_READY and "path" in event.data:
            self.publish_path([(p["x"], p["y"]) for p in event.data["path"]])

    def publish_path(self, points: Sequence[tuple[float, float]]) -> None:
        stamp = self._node.get_clock().now().to_msg()
        self._path_pub.publish(path_message(path_poses(points), self.frame_id, stamp))

    def publish_objects(self) -> None:
        """Send the objects when they changed since the last time (positions, names, how
        sure); an unchanged set is not sent again (the topic keeps the last one)."""
        objects = robot_objects(self._agent.robot)
        with self._lock:
            if objects == self._objects:
                return
            self._objects = objects
        stamp = self._node.get_clock().now().to_msg()
        self._objects_pub.publish(marker_array(object_markers(objects), self.frame_id, stamp))

    def close(self) -> None:
        self._unsubscribe()
        if self._timer is not None:
            self._timer.cancel()
