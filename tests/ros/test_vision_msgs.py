"""vision_msgs as the project ships it (ros2/vision_msgs: Detection2DArray and the types it is
made of) is ROS 2 Jazzy's vision_msgs: the same type hashes, so go2_ros2_sdk's coco_detector
(which publishes vision_msgs/Detection2DArray) and the Go2 robot's subscription match over DDS.
A copy that differed in one field name or type would get another hash and never connect.

How the expected hashes were computed: vision_msgs' own definitions (ros-perception/vision_msgs,
branch ros2, release 4.1.1, the one in Jazzy; vision_msgs/msg/{Detection2DArray, Detection2D,
ObjectHypothesisWithPose, ObjectHypothesis, BoundingBox2D, Pose2D, Point2D}.msg) run through
rosidl's own generators with

    python scripts/type_hash.py vision_msgs path/to/vision_msgs/msg/*.msg    # those seven

which prints the hashes below (std_msgs, geometry_msgs and builtin_interfaces come from the
installed Jazzy packages).

Skipped without rclpy or vision_msgs unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.ros.needs import require

require("rclpy", "vision_msgs", "rosidl_generator_type_description")

from tests.ros.rosclient import ROOT, RosClient, wait_until  # noqa: E402
from tests.ros.type_hashes import computed, installed  # noqa: E402

VISION_JAZZY = {
    "vision_msgs/msg/BoundingBox2D": "RIHS01_008eacbb0cf8f26e83795547bed013eec3675485ef386ec056d80eaaf1c1ce2f",  # noqa: E501
    "vision_msgs/msg/Detection2D": "RIHS01_0d12b69df5c593b3455b7346fac8205437a7d4bcb09b9e0e0b2dde787ded38ea",  # noqa: E501
    "vision_msgs/msg/Detection2DArray": "RIHS01_214274120007f4a683866481336b70310268cfa107aebe9d594a6acf75bda968",  # noqa: E501
    "vision_msgs/msg/ObjectHypothesis": "RIHS01_51da43cec11c01957a64d1e05a24acd18aae7745ec30b74348ad5f6d634f7f90",  # noqa: E501
    "vision_msgs/msg/ObjectHypothesisWithPose": "RIHS01_41c12344c0396c48b81df12467c192d99b2a0eb1463c5c37194e4223251c80bc",  # noqa: E501
    "vision_msgs/msg/Point2D": "RIHS01_eab0e83f44ab4de92ceaf76dd7d0e7638f2bdd1d16ffbe16c7a136c48e407247",  # noqa: E501
    "vision_msgs/msg/Pose2D": "RIHS01_b0b5d1d7b4c20dd4fcde3ed1d4b289a919290572007d67a97043814db25d3648",  # noqa: E501
}
MSG = ROOT / "ros2" / "vision_msgs" / "msg"
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


def test_our_definitions_hash_as_vision_msgs_jazzys() -> None:
    assert computed("vision_msgs", *sorted(MSG.glob("*.msg"))) == VISION_JAZZY


def test_the_installed_package_carries_vision_msgs_jazzys_hashes() -> None:
    import vision_msgs

    for name, expected in VISION_JAZZY.items():
        hashes = installed(vision_msgs.__file__, "vision_msgs", "msg", name.rsplit("/", 1)[1])
        assert hashes[name] == expected, name


def test_a_copy_with_one_other_field_type_hashes_differently(tmp_path: Path) -> None:
    # The check can fail: a float32 score (a plausible slip) is another type, and so is every
    # type that holds it, while the box is untouched.
    for file in MSG.glob("*.msg"):
        text = file.read_text()
        if file.name == "ObjectHypothesis.msg":
            text = text.replace("float64 score", "float32 score")
        (tmp_path / file.name).write_text(text)
    hashes = computed("vision_msgs", *sorted(tmp_path.glob("*.msg")))
    for changed in ("ObjectHypothesis", "ObjectHypothesisWithPose", "Detection2DArray"):
        name = f"vision_msgs/msg/{changed}"
        assert hashes[name] != VISION_JAZZY[name]
    name = "vision_msgs/msg/BoundingBox2D"
    assert hashes[name] == VISION_JAZZY[name]


def test_dds_announces_vision_msgs_jazzys_hash() -> None:
    from vision_msgs.msg import Detection2DArray

    client = RosClient("shadowhound_vision_msgs_test")
    try:
        topic = "/hash_check/detected_objects"
        client.publisher(Detection2DArray, topic)
        info = wait_until(
            lambda: client.node.get_publishers_info_by_topic(topic),
            10,
            "the detections publisher in the graph",
        )
        assert str(info[0].topic_type_hash) == VISION_JAZZY["vision_msgs/msg/Detection2DArray"]
    finally:
        client.close()
