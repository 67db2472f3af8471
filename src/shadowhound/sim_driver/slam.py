"""The simulated driver's SLAM (`shadowhound sim-driver --slam`): odometry that drifts as a
legged robot's does, and /tf as go2_ros2_sdk's driver (odom -> base_link) and slam_toolbox
(map -> odom) publish it. ROS is imported where it is used: the odometer is pure Python.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from ..errors import ParameterError
from ..state import compose, inverse

if TYPE_CHECKING:
    from rclpy.node import Node

    from .faults import Faults
    from .sport import Truth

__all__ = ["DriftingOdometer", "Pose", "SimSlam"]

Pose = tuple[float, float, float]


class DriftingOdometer:
    """Odometry that drifts as a legged robot's does: each true step (in the body frame) shows
    as `1 + drift` of it, in distance and in heading, so the error grows with the path walked.
    With drift 0 it reports the truth. Fed one true pose per odometry sample."""

    def __init__(self, drift: float) -> None:
        self.drift = drift
        self.pose: Pose = (0.0, 0.0, 0.0)
        self._last: Pose | None = None

    def update(self, truth: Pose) -> Pose:
        if self.drift == 0.0:
            self.pose = truth
            return truth
        if self._last is None:
            self._last = self.pose = truth
            return truth
        step = compose(inverse(self._last), truth)  # the true step, in the body frame
        scale = 1.0 + self.drift
        self._last = truth
        self.pose = compose(self.pose, (step[0] * scale, step[1] * scale, step[2] * scale))
        return self.pose


def tf_publisher(node: Node, slam: bool) -> Any:
    """/tf's publisher, or None without tf2_msgs (then only --slam needs it)."""
    from rclpy.qos import QoSProfile

    try:
        from tf2_msgs.msg import TFMessage
    except ImportError as exc:
        if slam:
            raise ParameterError(
                f"--slam publishes /tf, which needs the tf2_msgs package: run "
                f"scripts/build_ros.sh ({exc})"
            ) from exc
        return None
    return node.create_publisher(TFMessage, "/tf", QoSProfile(depth=100))


def tf_message(stamp: Any, edges: list[tuple[str, str, Pose]]) -> Any:
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage  # importable: there is a /tf publisher

    msg = TFMessage()
    for parent, child, (x, y, yaw) in edges:
        t = TransformStamped()
        t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, parent, child
        t.transform.translation.x, t.transform.translation.y = float(x), float(y)
        t.transform.rotation.z, t.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        msg.transforms.append(t)
    return msg


class SimSlam:
    """One robot's /tf: odom -> base_link with each odometry sample (as the driver broadcasts
    it) and, with `slam`, map -> odom of the same moment: the truth over the drifting odometry,
    off by any `slam_error` fault. `published` is what went out last, for the truth record."""

    def __init__(self, node: Node, slam: bool, drift: float) -> None:
        self.slam = slam
        self.odometer = DriftingOdometer(drift)
        self._pub = tf_publisher(node, slam)
        self.published: dict[str, Any] = {}

    def true_map_odom(self, t: Truth) -> Pose:
        """Where odometry's frame lies in the true world (the map) now: what a perfect SLAM
        would publish as map -> odom."""
        return compose((t.x, t.y, t.yaw), inverse(self.odometer.pose))

    def publish(
        self, stamp: Any, child: str, t: Truth, shown: Pose, odom: Pose, faults: Faults
    ) -> None:
        """For one odometry sample: `shown` is what odometry published, `odom` the drifting
        odometry before any lie, `t` the truth it was taken from."""
        if self._pub is None:
            return
        edges = [("odom", child, shown)]
        correction = None
        if self.slam:
            correction = compose((t.x, t.y, t.yaw), inverse(odom))
            if faults.slam_error is not None:  # SLAM mislocalized: its map is off by it
                correction = compose(faults.slam_error, correction)
            edges.insert(0, ("map", "odom", correction))
        self._pub.publish(tf_message(stamp, edges))
        self.published = {
            "odometry": {"x": shown[0], "y": shown[1], "yaw": shown[2]},
            "map_odom": None
            if correction is None
            else {"x": correction[0], "y": correction[1], "yaw": correction[2]},
        }
