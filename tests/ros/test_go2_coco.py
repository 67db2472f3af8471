"""A mission through a 2-D detector, over DDS, judged by the simulated driver's ground truth
(issue 24): `shadowhound sim-driver --detector coco` publishes what its camera sees as
go2_ros2_sdk's coco_detector does (vision_msgs/Detection2DArray boxes in pixels under COCO
names, on `detected_objects`, with `camera/camera_info`), and `shadowhound node -p robot:=go2
-p coco_detections_topic:=detected_objects` places each box with the camera model, the scan and
odometry. "go to the chair" (the scene's yellow chair stands behind the robot: a search first)
ends the standoff from the true chair, facing it.

Skipped without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "nav2_msgs", "vision_msgs")

from shadowhound.robot.scene import DEFAULT_WORLD  # noqa: E402
from tests.ros.rosclient import RosClient  # noqa: E402
from tests.ros.test_go2_truth import Rig, start_rig  # noqa: E402

CHAIR = DEFAULT_WORLD.find("yellow chair")
assert CHAIR is not None
STANDOFF = 0.6  # metres from the object's surface (search.standoff's default)
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_coco_client")
    yield c
    c.close()


@pytest.fixture(scope="module")
def rig(client: RosClient) -> Iterator[Rig]:
    rig, stop = start_rig(
        client,
        ("--detector", "coco"),
        "/coco",
        "/coco",
        "coco",
        "-p",
        "coco_detections_topic:=detected_objects",
        "-p",
        "camera_x:=0.0",  # the simulated camera sits at the body's centre
    )
    yield rig
    stop()


def test_go_to_the_chair_ends_the_standoff_from_the_true_chair(rig: Rig) -> None:
    final = rig.agent.run("go to the chair", 120.0)
    end = rig.truth.still()
    assert final.startswith("COMPLETED: "), (final, rig.node.output()[-3000:])
    gap = math.dist((end["x"], end["y"]), (CHAIR.x, CHAIR.y)) - CHAIR.radius
    assert abs(gap - STANDOFF) < 0.15, (gap, end, final)
    facing = math.atan2(CHAIR.y - end["y"], CHAIR.x - end["x"])
    assert abs(math.degrees(math.remainder(end["yaw"] - facing, math.tau))) < 10.0, end
