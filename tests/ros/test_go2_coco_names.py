"""Over DDS, with go2_ros2_sdk's coco_detector as `shadowhound sim-driver --detector coco` plays
it, a person names a thing by the COCO name docs/go2.md gives ("the ball `sports ball`"): "go to
the sports ball" goes to the ball the detector reported, judged by the driver's truth (it was
refused: the node's word for that class is "ball").

Skipped without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "nav2_msgs", "vision_msgs")

from shadowhound.robot.sim.scene import DEFAULT_WORLD  # noqa: E402
from shadowhound.sim_driver.detector import coco_class  # noqa: E402
from tests.ros.rosclient import RosClient  # noqa: E402
from tests.ros.test_go2_truth import start_rig  # noqa: E402

BALL = DEFAULT_WORLD.find("red ball")
assert BALL is not None
STANDOFF = 0.6  # metres from the object's surface (search.standoff's default)
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_coco_names_client")
    yield c
    c.close()


def test_go_to_the_sports_ball_ends_the_standoff_from_the_true_ball(client: RosClient) -> None:
    assert coco_class(BALL.name) == "sports ball"  # what the detector calls it
    rig, stop = start_rig(
        client,
        ("--detector", "coco"),
        "/coconames",
        "/coconames",
        "coconames",
        "-p",
        "coco_detections_topic:=detected_objects",
        "-p",
        "camera_x:=0.0",  # the simulated camera sits at the body's centre
    )
    try:
        final = rig.agent.run("go to the sports ball", 120.0)
        end = rig.truth.still()
        assert final.startswith("COMPLETED: "), (final, rig.node.output()[-3000:])
        gap = math.dist((end["x"], end["y"]), (BALL.x, BALL.y)) - BALL.radius
        assert abs(gap - STANDOFF) < 0.15, (gap, end, final)
        facing = math.atan2(BALL.y - end["y"], BALL.x - end["x"])
        assert abs(math.degrees(math.remainder(end["yaw"] - facing, math.tau))) < 10.0, end
    finally:
        stop()
