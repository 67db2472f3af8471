"""nav2_msgs/action/NavigateToPose as the project ships it (ros2/nav2_msgs) is Nav2 Jazzy's: the
same type hashes, so a real Nav2 and ShadowHound's client (or `shadowhound sim-driver`'s server)
match over DDS. A copy that differed in one field name or type would get another hash, and the
action's topics and services would never connect.

How the expected hashes were computed: Nav2 Jazzy's own definition (ros-navigation/navigation2,
branch jazzy, nav2_msgs/action/NavigateToPose.action, last changed by "Add string error_msg to
all action result messages", June 2024, in every Jazzy release since 1.3.1) run through
rosidl's own generators with

    python scripts/type_hash.py nav2_msgs path/to/navigation2/nav2_msgs/action/NavigateToPose.action

which prints the hashes below (the referenced geometry_msgs, builtin_interfaces, action_msgs
and unique_identifier_msgs descriptions come from the installed Jazzy packages).

Skipped without rclpy or nav2_msgs unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.ros.needs import require

require("rclpy", "nav2_msgs", "rosidl_generator_type_description")

from tests.ros.rosclient import ROOT, RosClient, wait_until  # noqa: E402
from tests.ros.type_hashes import computed, installed  # noqa: E402

NAV2_JAZZY = {
    "nav2_msgs/action/NavigateToPose": "RIHS01_a56dba8a3234a1215e610180dc703ae25bbf406dded8b54887891c9732857eab",  # noqa: E501
    "nav2_msgs/action/NavigateToPose_Goal": "RIHS01_22a9dffbd6733011220460bd52edbc7843c8fc86282d40bc7ad3ca176a9dec10",  # noqa: E501
    "nav2_msgs/action/NavigateToPose_Result": "RIHS01_ddbff7fc6d1e51d774d5defdb8398a57cb23fa8709355002d676408bb4860b85",  # noqa: E501
    "nav2_msgs/action/NavigateToPose_Feedback": "RIHS01_9ebc544c7d41bd8c6060b191bf9f5e4ddca6c2f61ee9e04fcb62ed5d67218a33",  # noqa: E501
    "nav2_msgs/action/NavigateToPose_FeedbackMessage": "RIHS01_9d1f6fa2eb975ce733b419ac2e97b134d8ff92b6478b6559feed9a50bdfd82b3",  # noqa: E501
    "nav2_msgs/action/NavigateToPose_SendGoal": "RIHS01_a4fcb3bee1bf32e21a0e541a943b221aa0826996e2c98f079b47022b256f48b5",  # noqa: E501
    "nav2_msgs/action/NavigateToPose_GetResult": "RIHS01_c407920357d566771e8882b4ef4d1f1a84ee922d609920ccd57faa6d6e391dc5",  # noqa: E501
}
OURS = ROOT / "ros2" / "nav2_msgs" / "action" / "NavigateToPose.action"
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


def test_our_definition_hashes_as_nav2_jazzys() -> None:
    hashes = computed("nav2_msgs", OURS)
    assert {name: hashes[name] for name in NAV2_JAZZY} == NAV2_JAZZY


def test_the_built_package_carries_nav2_jazzys_hashes() -> None:
    import nav2_msgs

    hashes = installed(nav2_msgs.__file__, "nav2_msgs", "action", "NavigateToPose")
    assert {name: hashes[name] for name in NAV2_JAZZY} == NAV2_JAZZY


def test_a_copy_with_one_other_field_type_hashes_differently(tmp_path: Path) -> None:
    # The check can fail: distance_remaining as float64 (a plausible slip) is another type.
    wrong = tmp_path / "NavigateToPose.action"
    wrong.write_text(
        OURS.read_text().replace("float32 distance_remaining", "float64 distance_remaining")
    )
    hashes = computed("nav2_msgs", wrong)
    assert (
        hashes["nav2_msgs/action/NavigateToPose_Feedback"]
        != NAV2_JAZZY["nav2_msgs/action/NavigateToPose_Feedback"]
    )
    assert (
        hashes["nav2_msgs/action/NavigateToPose_Goal"]
        == NAV2_JAZZY["nav2_msgs/action/NavigateToPose_Goal"]
    )


def test_dds_announces_nav2_jazzys_feedback_hash() -> None:
    from nav2_msgs.action import NavigateToPose

    client = RosClient("shadowhound_nav2_msgs_test")
    try:
        topic = "/hash_check/navigate_to_pose/_action/feedback"
        client.publisher(NavigateToPose.Impl.FeedbackMessage, topic)
        info = wait_until(
            lambda: client.node.get_publishers_info_by_topic(topic),
            10,
            "the feedback publisher in the graph",
        )
        assert (
            str(info[0].topic_type_hash)
            == NAV2_JAZZY["nav2_msgs/action/NavigateToPose_FeedbackMessage"]
        )
    finally:
        client.close()
