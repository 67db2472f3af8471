"""One simulated Go2's topics over Unitree's own ROS 2 interface (unitree_ros2, a Go2 EDU over
CycloneDDS), for `shadowhound sim-driver --interface unitree_ros2`:

- `api/sport/request` (unitree_api/Request) in: `header.identity.api_id` is the sport API id
  (the same table as go2_ros2_sdk's), `parameter` JSON ('' or, for Move, {"x","y","z"}); the
  robot acts on it at once (there is no driver's 10 Hz queue between);
  `api/sport/response` (unitree_api/Response) out: one answer per request, status code 0 when
  the robot acted on it, else 1 (with the reason in `data`);
- `lf/sportmodestate` (unitree_go/SportModeState) out: mode, progress, position (odom frame;
  z: body height), velocity (odom frame), yaw_speed, imu_state.rpy (yaw) and its quaternion,
  body_height; as the robot was `odom_delay` ago;
- `lf/lowstate` (unitree_go/LowState) out: `bms_state.soc` (percent charge).

The robot itself (its sport service, truth and faults) is the one of `go2.SimGo2`; this only
puts unitree_ros2's messages around it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from rclpy.qos import QoSProfile, ReliabilityPolicy
from unitree_api.msg import Request, Response
from unitree_go.msg import LowState, SportModeState

from ..robot.go2.api import SportMode
from ..state import Posture
from .sport import Truth

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = ["REQUEST_TOPIC", "UnitreeLink"]

REQUEST_TOPIC = "api/sport/request"
RESPONSE_TOPIC = "api/sport/response"
STATE_TOPIC = "lf/sportmodestate"
LOW_STATE_TOPIC = "lf/lowstate"
_RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)

Accept = Callable[[int, str, Callable[[bool, str], None]], None]


class UnitreeLink:
    """unitree_ros2's topics of one simulated robot on `node`; `topic(name)` resolves a name
    with the robot's prefix; `accept(api_id, parameter, answer)` hands a request on."""

    def __init__(self, node: Node, topic: Callable[[str], str], accept: Accept) -> None:
        self.node = node
        self._accept = accept
        self._state_pub = node.create_publisher(SportModeState, topic(STATE_TOPIC), _RELIABLE)
        self._low_pub = node.create_publisher(LowState, topic(LOW_STATE_TOPIC), _RELIABLE)
        self._response_pub = node.create_publisher(Response, topic(RESPONSE_TOPIC), _RELIABLE)
        self.request_topic = topic(REQUEST_TOPIC)
        node.create_subscription(Request, self.request_topic, self._on_request, _RELIABLE)

    def _on_request(self, msg: Request) -> None:
        identity = msg.header.identity
        request_id, api_id = int(identity.id), int(identity.api_id)
        self._accept(
            api_id, str(msg.parameter), lambda ok, note: self._answer(request_id, api_id, ok, note)
        )

    def _answer(self, request_id: int, api_id: int, accepted: bool, note: str) -> None:
        answer = Response()
        answer.header.identity.id, answer.header.identity.api_id = request_id, api_id
        answer.header.status.code = 0 if accepted else 1
        answer.data = "" if accepted else json.dumps({"error": note})
        self._response_pub.publish(answer)

    def publish_state(self, t: Truth, progress: int) -> None:
        """SportModeState of the true `t` (odom frame)."""
        c, s = math.cos(t.yaw), math.sin(t.yaw)
        standing = t.posture is Posture.STANDING and not t.changing
        msg = SportModeState()
        stamp = self.node.get_clock().now().nanoseconds
        msg.stamp.sec, msg.stamp.nanosec = divmod(stamp, 1_000_000_000)
        msg.mode = t.mode
        msg.progress = float(progress)
        msg.gait_type = 1 if t.mode == SportMode.LOCOMOTION else 0
        msg.foot_raise_height = 0.08 if standing else 0.0
        msg.position = [t.x, t.y, t.body_height]
        msg.body_height = t.body_height
        msg.velocity = [t.vx * c - t.vy * s, t.vx * s + t.vy * c, 0.0]
        msg.yaw_speed = t.wz
        msg.imu_state.rpy = [0.0, 0.0, t.yaw]
        msg.imu_state.quaternion = [math.cos(t.yaw / 2.0), 0.0, 0.0, math.sin(t.yaw / 2.0)]
        self._state_pub.publish(msg)

    def publish_low_state(self, percent: float) -> None:
        """LowState with the battery's charge (the rest left zero)."""
        msg = LowState()
        msg.bms_state.soc = max(0, min(100, round(percent)))
        self._low_pub.publish(msg)
