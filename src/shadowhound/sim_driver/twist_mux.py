"""A twist_mux-like relay, as go2_ros2_sdk's launch starts it (config/twist_mux.yaml):
`cmd_vel` (priority 5) and `cmd_vel_joy` (priority 10), 0.5 s timeouts, out to `cmd_vel_out`.

Like twist_mux, each message (zero Twists included) is forwarded at once unless an input of
higher priority has had a message within its timeout; nothing is published when inputs go
quiet. The node is named `twist_mux` and is not namespaced by the driver's robot layout.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from geometry_msgs.msg import Twist
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


@dataclass
class MuxInput:
    """One input topic: its priority, its timeout, and when it last spoke."""

    topic: str
    priority: int
    timeout: float
    last: float = -1e18


def forwards(inputs: list[MuxInput], source: MuxInput, now: float) -> bool:
    """Whether a message just received on `source` goes out: no other input of higher
    priority has spoken within its timeout."""
    return not any(
        i.priority > source.priority and now - i.last <= i.timeout
        for i in inputs
        if i is not source
    )


class TwistMux(Node):
    """`cmd_vel` and `cmd_vel_joy` in, `cmd_vel_out` out, by priority."""

    def __init__(self, timeout: float = 0.5, **node_kwargs: Any) -> None:
        super().__init__("twist_mux", **node_kwargs)
        self.inputs = [MuxInput("cmd_vel_joy", 10, timeout), MuxInput("cmd_vel", 5, timeout)]
        self._out = self.create_publisher(Twist, "cmd_vel_out", _QOS)
        for source in self.inputs:
            self.create_subscription(Twist, source.topic, self._relay(source), _QOS)

    def _relay(self, source: MuxInput) -> Callable[[Twist], None]:
        def on_twist(msg: Twist) -> None:
            now = time.monotonic()
            source.last = now
            if forwards(self.inputs, source, now):
                self._out.publish(msg)

        return on_twist
