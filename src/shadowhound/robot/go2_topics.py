"""Which topic a Go2's velocity commands must go to, from who subscribes (pure Python).

go2_ros2_sdk's driver node listens on `cmd_vel_out` (`robot{i}/cmd_vel_out` with several
robots). `cmd_vel` reaches it only through twist_mux, which robot.launch.py starts with
teleop, not namespaced. So: `cmd_vel` when something subscribes it (twist_mux, or the
simulated driver's relay), else `cmd_vel_out`, both relative to the robot's namespace.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

TWIST_TYPE = "geometry_msgs/msg/Twist"
VELOCITY_TOPICS = ("cmd_vel", "cmd_vel_out")  # in order of preference


def choose_velocity_topic(subscribers: Mapping[str, Sequence[tuple[str, str]]]) -> str | None:
    """The first of VELOCITY_TOPICS with a Twist subscriber; None when nothing listens yet.

    `subscribers` maps each topic name to its subscriptions as (node name, type name).
    """
    for name in VELOCITY_TOPICS:
        if any(kind == TWIST_TYPE for _node, kind in subscribers.get(name, ())):
            return name
    return None
