"""Which velocity topic reaches a go2_ros2_sdk driver, from who subscribes."""

from __future__ import annotations

from shadowhound.robot.go2_topics import TWIST_TYPE, choose_velocity_topic


def test_cmd_vel_when_twist_mux_subscribes_it() -> None:
    found = {
        "cmd_vel": [("twist_mux", TWIST_TYPE)],
        "cmd_vel_out": [("go2_driver_node", TWIST_TYPE)],
    }
    assert choose_velocity_topic(found) == "cmd_vel"


def test_cmd_vel_out_when_only_the_driver_listens() -> None:
    """No twist_mux (teleop off), or several robots (twist_mux is not namespaced)."""
    assert (
        choose_velocity_topic({"cmd_vel": [], "cmd_vel_out": [("go2_driver_node", TWIST_TYPE)]})
        == "cmd_vel_out"
    )


def test_nothing_when_nobody_listens_or_with_the_wrong_type() -> None:
    assert choose_velocity_topic({}) is None
    assert choose_velocity_topic({"cmd_vel": [("x", "geometry_msgs/msg/TwistStamped")]}) is None
