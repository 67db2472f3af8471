"""tf2_msgs as the project ships it (ros2/tf2_msgs: TFMessage only) is ROS 2 Jazzy's tf2_msgs:
the same type hash, so /tf and /tf_static as go2_ros2_sdk's driver, slam_toolbox and
robot_state_publisher publish them match the Go2 robot's subscriptions over DDS. A copy that
differed in one field name or type would get another hash and never connect.

How the expected hash was computed: tf2_msgs' own definition (ros2/geometry2, branch jazzy,
tf2_msgs 0.36.4; tf2_msgs/msg/TFMessage.msg) run through rosidl's own generators with

    python scripts/type_hash.py tf2_msgs path/to/tf2_msgs/msg/TFMessage.msg

which prints the hash below (geometry_msgs, std_msgs and builtin_interfaces come from the
installed Jazzy packages).

Skipped without rclpy or tf2_msgs unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.ros.needs import require

require("rclpy", "tf2_msgs", "rosidl_generator_type_description")

from tests.ros.rosclient import ROOT, RosClient, wait_until  # noqa: E402
from tests.ros.type_hashes import computed, installed  # noqa: E402

TF2_JAZZY = {
    "tf2_msgs/msg/TFMessage": "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",  # noqa: E501
}
MSG = ROOT / "ros2" / "tf2_msgs" / "msg"
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


def test_our_definition_hashes_as_tf2_msgs_jazzys() -> None:
    assert computed("tf2_msgs", *sorted(MSG.glob("*.msg"))) == TF2_JAZZY


def test_the_installed_package_carries_tf2_msgs_jazzys_hash() -> None:
    import tf2_msgs

    for name, expected in TF2_JAZZY.items():
        hashes = installed(tf2_msgs.__file__, "tf2_msgs", "msg", name.rsplit("/", 1)[1])
        assert hashes[name] == expected, name


def test_a_copy_with_another_element_type_hashes_differently(tmp_path: Path) -> None:
    # The check can fail: a list of Transforms without their headers (a plausible slip) is
    # another type.
    text = (MSG / "TFMessage.msg").read_text()
    (tmp_path / "TFMessage.msg").write_text(
        text.replace("geometry_msgs/TransformStamped[]", "geometry_msgs/Transform[]")
    )
    hashes = computed("tf2_msgs", tmp_path / "TFMessage.msg")
    name = "tf2_msgs/msg/TFMessage"
    assert hashes[name] != TF2_JAZZY[name]


def test_dds_announces_tf2_msgs_jazzys_hash() -> None:
    from tf2_msgs.msg import TFMessage

    client = RosClient("shadowhound_tf2_msgs_test")
    try:
        topic = "/hash_check/tf"
        client.publisher(TFMessage, topic)
        info = wait_until(
            lambda: client.node.get_publishers_info_by_topic(topic),
            10,
            "the tf publisher in the graph",
        )
        assert str(info[0].topic_type_hash) == TF2_JAZZY["tf2_msgs/msg/TFMessage"]
    finally:
        client.close()
