"""Which topic a Go2's velocity commands must go to, from the ROS graph (pure Python).

go2_ros2_sdk's driver node listens on `cmd_vel_out` (`robot{i}/cmd_vel_out` with several
robots). `cmd_vel` reaches it only through a relay: a node that subscribes `cmd_vel` and
publishes `cmd_vel_out`, as twist_mux does (robot.launch.py starts it with teleop, not
namespaced). Anything else on `cmd_vel` (`ros2 topic echo`, a rosbag recorder, a foxglove
bridge) only listens, and a Twist sent there reaches no driver. So: `cmd_vel` when one node
both subscribes it and publishes `cmd_vel_out` (nodes matched by their full names), else
`cmd_vel_out`, both relative to the robot's namespace.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

TWIST_TYPE = "geometry_msgs/msg/Twist"
VELOCITY_TOPICS = ("cmd_vel", "cmd_vel_out")  # the relay's input, the driver's own
# topic -> its endpoints as (node's full name, type name)
Endpoints = Mapping[str, Sequence[tuple[str, str]]]
# What the rmw reports for an endpoint whose node it has not heard of yet: no relay by name.
UNKNOWN_NODE = "_NODE_NAME_UNKNOWN_"


@dataclass(frozen=True)
class VelocityRoute:
    """Where velocity goes and why; `reaches` is False when nothing listens there yet."""

    topic: str  # one of VELOCITY_TOPICS
    why: str
    reaches: bool = True

    def __str__(self) -> str:
        return f"{self.topic}: {self.why}"


def node_name(namespace: str, name: str) -> str:
    """A node's full name, as graph queries give its namespace and name apart."""
    return f"{namespace.rstrip('/')}/{name}"


def choose_velocity_topic(
    subscribers: Endpoints, publishers: Endpoints, names: Mapping[str, str] | None = None
) -> VelocityRoute:
    """`cmd_vel` when a relay carries it to `cmd_vel_out`, else `cmd_vel_out`.

    `subscribers` and `publishers` map topic names (VELOCITY_TOPICS) to their endpoints;
    `names` gives the topics' full names for the reason (default: as they are).
    """

    def shown(topic: str) -> str:
        return (names or {}).get(topic, topic)

    def twist_nodes(side: Endpoints, topic: str) -> list[str]:
        return sorted({node for node, kind in side.get(topic, ()) if kind == TWIST_TYPE})

    listeners = twist_nodes(subscribers, "cmd_vel")
    feeders = set(twist_nodes(publishers, "cmd_vel_out"))
    relays = [node for node in listeners if node in feeders and UNKNOWN_NODE not in node]
    if relays:
        return VelocityRoute("cmd_vel", f"{', '.join(relays)} relays it to {shown('cmd_vel_out')}")
    heard = (
        f"subscribers of {shown('cmd_vel')}: {', '.join(listeners)}"
        if listeners
        else f"nothing subscribes {shown('cmd_vel')}"
    )
    if not twist_nodes(subscribers, "cmd_vel_out"):
        return VelocityRoute(
            "cmd_vel_out",
            f"nothing subscribes {shown('cmd_vel_out')} and nothing relays "
            f"{shown('cmd_vel')} ({heard})",
            reaches=False,
        )
    return VelocityRoute("cmd_vel_out", f"nothing relays {shown('cmd_vel')} ({heard})")
