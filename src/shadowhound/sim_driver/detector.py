"""`shadowhound sim-driver` as a detector: what one simulated robot's camera sees, published as
shadowhound_interfaces/DetectionArray on its `detections` topic, as any detector bridged to the
Go2 robot's `detections_topic` would (docs/ros.md, "Detections").

With `--detector coco` it is instead a 2-D detector as go2_ros2_sdk's coco_detector is:
vision_msgs/Detection2DArray on `detected_objects`, each object in view as the box the
renderer draws it in (its angular width through the renderer's pinhole, in pixels of the
camera image), under its COCO category name (a chair "chair", a fridge "refrigerator", a plant
"potted plant"; objects COCO has no class for are not reported), with camera_info (best
effort) describing that camera. The camera sits at the body's centre (run the node with
`-p camera_x:=0.0`).

What is in view is the simulator's own camera rule (`scene.visible_objects`: field of view,
range, occlusion), so the detections, the camera's sightings, the image and the scan agree.
Each object is reported at its true centre in the odometry frame (the driver's odometry is the
truth, late), with its true radius and confidence 1. shadowhound_interfaces is optional: without
it the driver runs on with a warning and no detections.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

from ..robot.sim import scene
from ..state import Pose2D

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = [
    "CAMERA_FOV_DEG",
    "COCO_OF",
    "ODOM_FRAME",
    "CocoDetector",
    "SimDetector",
    "coco_class",
    "in_view",
]

ODOM_FRAME = "odom"  # as the driver's odometry names it
_RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
_SENSOR = QoSProfile(
    depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
CAMERA_FOV_DEG = 90.0  # the simulated camera's field of view (renderer.render's default)
# The COCO category a scene object's kind (the last word of its name) is reported as.
COCO_OF = {
    "chair": "chair",
    "sofa": "couch",
    "couch": "couch",
    "table": "dining table",
    "plant": "potted plant",
    "fridge": "refrigerator",
    "refrigerator": "refrigerator",
    "ball": "sports ball",
    "person": "person",
    "tv": "tv",
    "television": "tv",
    "bottle": "bottle",
    "bed": "bed",
}


def coco_class(name: str) -> str | None:
    """The COCO category a coco_detector would report `name` as, or None (no such class)."""
    words = name.lower().split()
    return COCO_OF.get(words[-1]) if words else None


def in_view(world: scene.World, pose: Pose2D) -> list[scene.WorldObject]:
    """The objects of `world` the camera at `pose` sees, nearest first."""
    found = (world.find(s.name) for s in scene.visible_objects(world, pose))
    return [obj for obj in found if obj is not None]


class SimDetector:
    """The `detections` publisher of one simulated robot (`topic` resolved already): true
    centres in `frame` (odom, whose origin is the truth's; map with --slam, as odom drifts)."""

    def __init__(self, node: Node, publisher: Any, frame: str = ODOM_FRAME) -> None:
        self.node, self._publisher, self.frame = node, publisher, frame

    @classmethod
    def create(cls, node: Node, topic: str, frame: str = ODOM_FRAME) -> SimDetector | None:
        """The detector, or None (with a warning) when shadowhound_interfaces is missing."""
        try:
            from shadowhound_interfaces.msg import DetectionArray
        except ImportError as exc:
            node.get_logger().warning(
                "no detections: shadowhound_interfaces is not installed (run "
                f"scripts/build_ros.sh; --detector none hides this warning): {exc}"
            )
            return None
        return cls(node, node.create_publisher(DetectionArray, topic, _RELIABLE), frame)

    def publish(self, world: scene.World, pose: Pose2D) -> None:
        """One array: every object in view from `pose` (none: an empty array)."""
        from shadowhound_interfaces.msg import Detection, DetectionArray

        msg = DetectionArray()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.header.frame_id = self.frame
        for obj in in_view(world, pose):
            d = Detection(label=obj.name, confidence=1.0, radius=float(obj.radius))
            d.position.x, d.position.y = float(obj.x), float(obj.y)
            msg.detections.append(d)
        self._publisher.publish(msg)


class CocoDetector:
    """`detected_objects` (vision_msgs/Detection2DArray) and `camera/camera_info` of one
    simulated robot, for a camera `width` x `height` pixels with a `fov_deg` field of view."""

    def __init__(
        self, node: Node, boxes: Any, info: Any, width: int, height: int, fov_deg: float
    ) -> None:
        self.node, self._boxes, self._info = node, boxes, info
        self.width, self.height, self.fov = width, height, math.radians(fov_deg)
        self.fx = (width / 2.0) / math.tan(self.fov / 2.0)  # as the renderer projects
        self.cx, self.cy = width / 2.0, height / 2.0

    @classmethod
    def create(
        cls, node: Node, boxes_topic: str, info_topic: str, width: int, height: int, fov: float
    ) -> CocoDetector | None:
        """The detector, or None (with a warning) when vision_msgs is missing."""
        try:
            from vision_msgs.msg import Detection2DArray
        except ImportError as exc:
            node.get_logger().warning(
                "no COCO detections: vision_msgs is not installed (run "
                f"scripts/build_ros.sh; --detector none hides this warning): {exc}"
            )
            return None
        from sensor_msgs.msg import CameraInfo

        return cls(
            node,
            node.create_publisher(Detection2DArray, boxes_topic, _RELIABLE),
            node.create_publisher(CameraInfo, info_topic, _SENSOR),
            width,
            height,
            fov,
        )

    def box(self, obj: scene.WorldObject, pose: Pose2D) -> tuple[float, float] | None:
        """The columns (left, right) `obj` spans in the image from `pose`, clipped to the
        image; None when none of it is in the field of view."""
        distance = pose.distance_to(obj.x, obj.y)
        centre = math.atan2(obj.y - pose.y, obj.x - pose.x) - pose.yaw
        centre = math.remainder(centre, math.tau)
        half = math.asin(min(1.0, obj.radius / distance))
        edge = self.fov / 2.0
        left, right = min(edge, centre + half), max(-edge, centre - half)
        if left <= right:
            return None
        return self.cx - self.fx * math.tan(left), self.cx - self.fx * math.tan(right)

    def publish(self, world: scene.World, pose: Pose2D) -> int:
        """One array (every COCO object in view from `pose`; none: an empty array) and the
        camera_info it was seen with, both stamped now. Returns how many boxes were sent."""
        from sensor_msgs.msg import CameraInfo
        from vision_msgs.msg import Detection2D, Detection2DArray, ObjectHypothesisWithPose

        stamp = self.node.get_clock().now().to_msg()
        msg = Detection2DArray()
        msg.header.stamp, msg.header.frame_id = stamp, "camera_link"
        for obj in in_view(world, pose):
            name, columns = coco_class(obj.name), self.box(obj, pose)
            if name is None or columns is None:
                continue
            d = Detection2D()
            hypothesis = ObjectHypothesisWithPose()
            hypothesis.hypothesis.class_id, hypothesis.hypothesis.score = name, 0.95
            d.results = [hypothesis]
            d.bbox.center.position.x = (columns[0] + columns[1]) / 2
            d.bbox.size_x = columns[1] - columns[0]
            distance = pose.distance_to(obj.x, obj.y)
            d.bbox.size_y = min(float(self.height), self.fx * obj.height / distance)
            d.bbox.center.position.y = self.cy
            msg.detections.append(d)
        info = CameraInfo()
        info.header.stamp, info.header.frame_id = stamp, "camera_link"
        info.width, info.height = self.width, self.height
        info.k = [self.fx, 0.0, self.cx, 0.0, self.fx, self.cy, 0.0, 0.0, 1.0]
        info.p = [self.fx, 0.0, self.cx, 0.0, 0.0, self.fx, self.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
        self._info.publish(info)
        self._boxes.publish(msg)
        return len(msg.detections)
