"""`shadowhound sim-driver` as a detector: what one simulated robot's camera sees, published as
shadowhound_interfaces/DetectionArray on its `detections` topic, as any detector bridged to the
Go2 robot's `detections_topic` would (docs/ros.md, "Detections").

What is in view is the simulator's own camera rule (`scene.visible_objects`: field of view,
range, occlusion), so the detections, the camera's sightings, the image and the scan agree.
Each object is reported at its true centre in the odometry frame (the driver's odometry is the
truth, late), with its true radius and confidence 1. shadowhound_interfaces is optional: without
it the driver runs on with a warning and no detections.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from rclpy.qos import QoSProfile, ReliabilityPolicy

from ..robot import scene
from ..state import Pose2D

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = ["ODOM_FRAME", "SimDetector", "in_view"]

ODOM_FRAME = "odom"  # as the driver's odometry names it
_RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def in_view(world: scene.World, pose: Pose2D) -> list[scene.WorldObject]:
    """The objects of `world` the camera at `pose` sees, nearest first."""
    found = (world.find(s.name) for s in scene.visible_objects(world, pose))
    return [obj for obj in found if obj is not None]


class SimDetector:
    """The `detections` publisher of one simulated robot (`topic` resolved already)."""

    def __init__(self, node: Node, publisher: Any) -> None:
        self.node, self._publisher = node, publisher

    @classmethod
    def create(cls, node: Node, topic: str) -> SimDetector | None:
        """The detector, or None (with a warning) when shadowhound_interfaces is missing."""
        try:
            from shadowhound_interfaces.msg import DetectionArray
        except ImportError as exc:
            node.get_logger().warning(
                "no detections: shadowhound_interfaces is not installed (run "
                f"scripts/build_ros.sh; --no-detections hides this warning): {exc}"
            )
            return None
        return cls(node, node.create_publisher(DetectionArray, topic, _RELIABLE))

    def publish(self, world: scene.World, pose: Pose2D) -> None:
        """One array: every object in view from `pose` (none: an empty array)."""
        from shadowhound_interfaces.msg import Detection, DetectionArray

        msg = DetectionArray()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.header.frame_id = ODOM_FRAME
        for obj in in_view(world, pose):
            d = Detection(label=obj.name, confidence=1.0, radius=float(obj.radius))
            d.position.x, d.position.y = float(obj.x), float(obj.y)
            msg.detections.append(d)
        self._publisher.publish(msg)
