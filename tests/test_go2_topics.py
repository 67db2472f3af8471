"""Which velocity topic reaches a go2_ros2_sdk driver, from the ROS graph (issue 23 item 2).

`cmd_vel` only when a relay (a node that subscribes `cmd_vel` and publishes `cmd_vel_out`, as
twist_mux does) carries it to the driver; a node that only listens on `cmd_vel` (`ros2 topic
echo`, a rosbag recorder, a foxglove bridge) reaches no driver.
"""

from __future__ import annotations

from shadowhound.robot.go2.topics import TWIST_TYPE, choose_velocity_topic

DRIVER = ("/go2_driver_node", TWIST_TYPE)
MUX = ("/twist_mux", TWIST_TYPE)


def test_cmd_vel_when_twist_mux_relays_it_to_the_driver() -> None:
    route = choose_velocity_topic(
        subscribers={"cmd_vel": [MUX], "cmd_vel_out": [DRIVER]},
        publishers={"cmd_vel_out": [MUX]},
    )
    assert (route.topic, route.reaches) == ("cmd_vel", True)
    assert str(route) == "cmd_vel: /twist_mux relays it to cmd_vel_out"


def test_cmd_vel_out_when_something_only_listens_on_cmd_vel() -> None:
    """An echo, a recorder or a bridge on cmd_vel is no relay: Twists there reach nothing."""
    route = choose_velocity_topic(
        subscribers={"cmd_vel": [("/echo", TWIST_TYPE)], "cmd_vel_out": [DRIVER]},
        publishers={"cmd_vel_out": []},
    )
    assert (route.topic, route.reaches) == ("cmd_vel_out", True)
    assert str(route) == "cmd_vel_out: nothing relays cmd_vel (subscribers of cmd_vel: /echo)"


def test_a_relay_is_one_node_on_both_topics_matched_by_its_full_name() -> None:
    """A listener on cmd_vel and another node publishing cmd_vel_out (ShadowHound itself, a
    joystick) make no relay; nor does a node of the same name in another namespace."""
    route = choose_velocity_topic(
        subscribers={
            "cmd_vel": [("/echo", TWIST_TYPE), ("/robot1/twist_mux", TWIST_TYPE)],
            "cmd_vel_out": [DRIVER],
        },
        publishers={"cmd_vel_out": [("/shadowhound_go2", TWIST_TYPE), ("/twist_mux", TWIST_TYPE)]},
    )
    assert route.topic == "cmd_vel_out"
    assert "subscribers of cmd_vel: /echo, /robot1/twist_mux" in route.why


def test_endpoints_of_nodes_not_known_yet_make_no_relay() -> None:
    """DDS may report an endpoint before its node's name: two such are no one node."""
    unknown = ("_NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_", TWIST_TYPE)
    route = choose_velocity_topic(
        subscribers={"cmd_vel": [unknown], "cmd_vel_out": [DRIVER]},
        publishers={"cmd_vel_out": [unknown]},
    )
    assert route.topic == "cmd_vel_out"


def test_cmd_vel_out_when_only_the_driver_listens() -> None:
    """No twist_mux (teleop off), or several robots (twist_mux is not namespaced)."""
    route = choose_velocity_topic(subscribers={"cmd_vel_out": [DRIVER]}, publishers={})
    assert str(route) == "cmd_vel_out: nothing relays cmd_vel (nothing subscribes cmd_vel)"


def test_names_in_the_reason_are_the_full_topic_names_given() -> None:
    names = {"cmd_vel": "/robot0/cmd_vel", "cmd_vel_out": "/robot0/cmd_vel_out"}
    route = choose_velocity_topic(subscribers={"cmd_vel_out": [DRIVER]}, publishers={}, names=names)
    assert route.why == "nothing relays /robot0/cmd_vel (nothing subscribes /robot0/cmd_vel)"


def test_nothing_reached_when_nobody_listens_or_with_the_wrong_type() -> None:
    """The driver's own cmd_vel_out, marked as reaching nothing (the driver is not up yet)."""
    for subscribers, publishers in (
        ({}, {}),
        ({"cmd_vel": [("/echo", TWIST_TYPE)]}, {}),
        (
            {"cmd_vel": [("/x", "geometry_msgs/msg/TwistStamped")]},
            {"cmd_vel_out": [("/x", "geometry_msgs/msg/TwistStamped")]},
        ),
    ):
        route = choose_velocity_topic(subscribers=subscribers, publishers=publishers)
        assert (route.topic, route.reaches) == ("cmd_vel_out", False), route
        assert "nothing subscribes cmd_vel_out" in route.why
