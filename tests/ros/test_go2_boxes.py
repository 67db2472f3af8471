"""The Go2 robot's intake of a 2-D detector's boxes over DDS: vision_msgs/Detection2DArray (as
go2_ros2_sdk's coco_detector publishes it on `detected_objects`) with camera_info (best
effort), odometry and the scan becomes a known object where the object stands, under the
planner's name; a box with nothing in range is a bearing only, never a known object.

The test publishes what a driver and a detector would, stamped with its clock, again on each
poll until the robot reports the result (the subscriptions are best effort: what is sent before
DDS has matched them is lost, so the test waits on the effect, never on time).

Skipped without rclpy, go2_interfaces or vision_msgs unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "vision_msgs")

from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import CameraInfo, LaserScan  # noqa: E402
from vision_msgs.msg import Detection2D, Detection2DArray, ObjectHypothesisWithPose  # noqa: E402

from shadowhound.robot.go2.robot import Go2RosConfig, Go2RosRobot  # noqa: E402
from shadowhound.robot.go2.world_msgs import scan_to_msg  # noqa: E402
from shadowhound.robot.sim.scene import World, WorldObject  # noqa: E402
from shadowhound.robot.sim.sensors import cast_scan  # noqa: E402
from shadowhound.state import Pose2D  # noqa: E402
from shadowhound.world.image_sighting import CameraModel  # noqa: E402
from tests.ros.rosclient import RosClient, wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
NS = "boxes"
SENSOR = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
CAMERA = CameraModel(fx=370.0, cx=640.0, x=0.3)
POSE = Pose2D(1.0, -0.5, 0.4)  # where the robot stands, in odom
CHAIR = WorldObject("dining table", 3.5, 0.8, 0.45)
WORLD = World(objects=(CHAIR,), bounds=(-8.0, 8.0, -8.0, 8.0))


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_boxes_test")
    yield c
    c.close()


@pytest.fixture(scope="module")
def robot(client: RosClient) -> Iterator[Go2RosRobot]:
    r = Go2RosRobot(
        Go2RosConfig(
            namespace=NS,
            node_name="shadowhound_go2_boxes",
            coco_detections_topic="detected_objects",
            camera_x=0.3,
            map_topic="",
            nav2_action="",
            estop_topic="",
        ),
        context=client.context,
    )
    yield r
    r.close()


def box(name: str, left: float, right: float, score: float = 0.92) -> Detection2D:
    d = Detection2D()
    hypothesis = ObjectHypothesisWithPose()
    hypothesis.hypothesis.class_id = name
    hypothesis.hypothesis.score = score
    d.results = [hypothesis]
    d.bbox.center.position.x = (left + right) / 2
    d.bbox.center.position.y = 360.0
    d.bbox.size_x = right - left
    d.bbox.size_y = 120.0
    return d


def test_a_box_becomes_a_known_object_where_it_stands_and_a_far_one_a_bearing(
    client: RosClient, robot: Go2RosRobot
) -> None:
    odom = client.publisher(Odometry, f"/{NS}/odom")
    scan_pub = client.publisher(LaserScan, f"/{NS}/scan", SENSOR)
    info_pub = client.publisher(CameraInfo, f"/{NS}/camera/camera_info", SENSOR)
    boxes = client.publisher(Detection2DArray, f"/{NS}/detected_objects")
    scan = cast_scan(WORLD, POSE)
    eye = CAMERA.origin(POSE)
    d = math.hypot(CHAIR.x - eye.x, CHAIR.y - eye.y)
    centre = math.atan2(CHAIR.y - eye.y, CHAIR.x - eye.x) - eye.yaw
    half = math.asin(CHAIR.radius / d)
    table = box("dining table", CAMERA.column_of(centre + half), CAMERA.column_of(centre - half))
    # A person straight to the right: the scan sees the wall 8 m off there, beyond 6 m.
    person = box("person", 1200.0, 1260.0)

    def publish() -> None:
        stamp = client.node.get_clock().now().to_msg()
        o = Odometry()
        o.header.stamp, o.header.frame_id, o.child_frame_id = stamp, "odom", "base_link"
        o.pose.pose.position.x, o.pose.pose.position.y = POSE.x, POSE.y
        o.pose.pose.orientation.z = math.sin(POSE.yaw / 2)
        o.pose.pose.orientation.w = math.cos(POSE.yaw / 2)
        odom.publish(o)
        scan_pub.publish(scan_to_msg(scan, "base_link", stamp, 0.1))
        info = CameraInfo()
        info.header.stamp, info.width, info.height = stamp, 1280, 720
        info.k = [CAMERA.fx, 0.0, CAMERA.cx, 0.0, CAMERA.fx, 360.0, 0.0, 0.0, 1.0]
        info_pub.publish(info)
        msg = Detection2DArray()
        msg.header.stamp, msg.header.frame_id = stamp, "front_camera"
        msg.detections = [table, person]
        boxes.publish(msg)

    def known() -> object:
        publish()
        return next((o for o in robot.known_objects() if o.name == "table"), None)

    found = wait_until(known, 30, "the table among the robot's known objects", interval=0.1)
    assert math.hypot(found.x - CHAIR.x, found.y - CHAIR.y) < 0.15, found
    assert found.confidence == pytest.approx(0.92)
    assert "person" not in {o.name for o in robot.known_objects()}  # a bearing only
    assert {"television", "sofa", "chair", "person"} <= robot.vocabulary()


@pytest.mark.parametrize(
    "obj, pose",
    [
        (WorldObject("chair", 3.0, 0.5, 0.4), Pose2D()),
        (WorldObject("chair", 1.5, 1.0, 0.3), Pose2D(0.2, -0.3, 0.3)),
        (WorldObject("chair", 2.0, -1.8, 0.35), Pose2D(0.0, 0.0, 0.0)),  # cut by the edge
    ],
)
def test_the_simulated_coco_box_is_where_the_renderer_draws_the_object(
    obj: WorldObject, pose: Pose2D
) -> None:
    from shadowhound.robot.sim.renderer import render
    from shadowhound.sim_driver.detector import CocoDetector

    width, height = 160, 120
    detector = CocoDetector(None, None, None, width, height, 90.0)  # type: ignore[arg-type]
    empty, full = World(), World(objects=(obj,))
    a, b = render(empty, pose, width, height), render(full, pose, width, height)
    drawn = [
        i
        for i in range(width)
        if any(
            a[3 * (r * width + i) : 3 * (r * width + i) + 3]
            != b[3 * (r * width + i) : 3 * (r * width + i) + 3]
            for r in range(height)
        )
    ]
    columns = detector.box(obj, pose)
    assert columns is not None and drawn
    # The box spans the columns drawn, to a pixel (a column is drawn when its centre ray hits).
    assert columns[0] == pytest.approx(drawn[0], abs=1.0)
    assert columns[1] == pytest.approx(drawn[-1] + 1, abs=1.0)
