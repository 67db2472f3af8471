"""The Go2 robot's inputs within their limits, over DDS (issue 32, items 4 and 7): a message
beyond its kind's size is refused unread, of one within it the 100 most confident boxes are read,
a scan of too many ranges is refused, a transform stamped from the future is refused, each said
in the robot's input report; honest sizes (a
lidar's scan, robot_state_publisher's links with SLAM's map -> odom) are taken as before.

The test publishes what a driver, SLAM and a detector would, again on each poll until the robot
reports the result (what is sent before DDS has matched is lost: the test waits on effects).

Skipped without rclpy, go2_interfaces, tf2_msgs or vision_msgs unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import array
import math
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "vision_msgs", "tf2_msgs")

from geometry_msgs.msg import TransformStamped  # noqa: E402
from rclpy.duration import Duration  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import serialize_message  # noqa: E402
from sensor_msgs.msg import CameraInfo, LaserScan  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402
from vision_msgs.msg import Detection2D, Detection2DArray, ObjectHypothesisWithPose  # noqa: E402

from shadowhound.robot.go2.robot import Go2RosConfig, Go2RosRobot  # noqa: E402
from shadowhound.robot.input_limits import MAX_BEAMS, MAX_BOXES, MAX_BYTES, size_words  # noqa: E402
from tests.ros.rosclient import RosClient, wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
NS = "inputs"
SENSOR = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_inputs_test")
    yield c
    c.close()


@pytest.fixture(scope="module")
def robot(client: RosClient) -> Iterator[Go2RosRobot]:
    r = Go2RosRobot(
        Go2RosConfig(
            namespace=NS,
            node_name="shadowhound_go2_inputs",
            coco_detections_topic="detected_objects",
            map_topic="",
            nav2_action="",
            estop_topic="",
        ),
        context=client.context,
    )
    yield r
    r.close()


def stamp(client: RosClient, ahead: float = 0.0) -> Any:
    return (client.node.get_clock().now() + Duration(seconds=ahead)).to_msg()


def scan(client: RosClient, beams: int) -> LaserScan:
    msg = LaserScan()
    msg.header.stamp, msg.header.frame_id = stamp(client), "base_link"
    msg.angle_min, msg.angle_increment = -math.pi, 2 * math.pi / beams
    msg.angle_max = msg.angle_min + (beams - 1) * msg.angle_increment
    msg.range_min, msg.range_max = 0.1, 10.0
    msg.ranges = array.array("f", [3.0] * beams)
    return msg


def transforms(client: RosClient, edges: list[tuple[str, str]], ahead: float = 0.0) -> TFMessage:
    msg = TFMessage()
    for parent, child in edges:
        t = TransformStamped()
        t.header.stamp, t.header.frame_id, t.child_frame_id = stamp(client, ahead), parent, child
        t.transform.translation.x = 0.1
        t.transform.rotation.w = 1.0
        msg.transforms.append(t)
    return msg


def boxes(client: RosClient, count: int) -> Detection2DArray:
    msg = Detection2DArray()
    msg.header.stamp, msg.header.frame_id = stamp(client), "front_camera"
    for i in range(count):
        d = Detection2D()
        hypothesis = ObjectHypothesisWithPose()
        hypothesis.hypothesis.class_id, hypothesis.hypothesis.score = "kite", 0.5
        d.results = [hypothesis]
        d.bbox.center.position.x, d.bbox.size_x = float(i % 1280), 8.0
        msg.detections.append(d)
    return msg


def reported(robot: Go2RosRobot, publish: Callable[[], None], words: str) -> str:
    """Publish until the robot's input report says `words`; the report."""

    def said() -> str:
        publish()
        problems = robot.input_problems
        return problems if words in problems else ""

    return str(wait_until(said, 30, f"the robot to report {words!r}", interval=0.2))


def test_honest_sizes_are_taken(client: RosClient, robot: Go2RosRobot) -> None:
    """A lidar's scan (1,440 beams), and robot_state_publisher's 30 links with SLAM's
    map -> odom: taken, nothing reported."""
    scan_pub = client.publisher(LaserScan, f"/{NS}/scan", SENSOR)
    tf = client.publisher(TFMessage, "/tf", TF_QOS)
    links = [("base_link", f"link_{i}") for i in range(30)]

    def taken() -> bool:
        scan_pub.publish(scan(client, 1440))
        tf.publish(transforms(client, [*links, ("map", "odom"), ("odom", "base_link")]))
        got = robot.get_scan()
        return got is not None and len(got.ranges) == 1440 and robot.world_frame == "map"

    wait_until(taken, 30, "the scan and the map frame taken", interval=0.2)
    assert robot.input_problems == ""


def test_a_scan_of_too_many_ranges_is_refused(client: RosClient, robot: Go2RosRobot) -> None:
    scan_pub = client.publisher(LaserScan, f"/{NS}/scan", SENSOR)
    words = f"{2 * MAX_BEAMS} ranges in one scan; at most {MAX_BEAMS} are read"
    report = reported(robot, lambda: scan_pub.publish(scan(client, 2 * MAX_BEAMS)), words)
    assert f"/{NS}/scan: dropped a scan: {words}" in report


def test_messages_beyond_their_size_are_refused_unread(
    client: RosClient, robot: Go2RosRobot
) -> None:
    box_pub = client.publisher(Detection2DArray, f"/{NS}/detected_objects", SENSOR)
    big = boxes(client, 1000)
    size, limit = size_words(len(serialize_message(big))), size_words(MAX_BYTES["detections"])
    report = reported(robot, lambda: box_pub.publish(big), "refused unread")
    assert (
        f"/{NS}/detected_objects: a Detection2DArray of {size} refused unread (at most {limit} "
        "is taken)"
    ) in report, report
    tf = client.publisher(TFMessage, "/tf", TF_QOS)
    many = transforms(client, [("base_link", f"link_{i}") for i in range(1000)])
    size, limit = size_words(len(serialize_message(many))), size_words(MAX_BYTES["tf"])
    report = reported(robot, lambda: tf.publish(many), "a TFMessage of")
    assert f"/tf: a TFMessage of {size} refused unread (at most {limit} is taken)" in report


def test_of_many_boxes_the_most_confident_are_read(client: RosClient, robot: Go2RosRobot) -> None:
    """120 boxes: within the size, read; the 100 most confident placed."""
    info_pub = client.publisher(CameraInfo, f"/{NS}/camera/camera_info", SENSOR)
    box_pub = client.publisher(Detection2DArray, f"/{NS}/detected_objects", SENSOR)

    def publish() -> None:
        info = CameraInfo()
        info.header.stamp, info.width, info.height = stamp(client), 1280, 720
        info.k = [370.0, 0.0, 640.0, 0.0, 370.0, 360.0, 0.0, 0.0, 1.0]
        info_pub.publish(info)
        box_pub.publish(boxes(client, 120))

    words = f"120 detections in one message: read the {MAX_BOXES} most confident"
    assert f"/{NS}/detected_objects: {words}" in reported(robot, publish, words)


def test_a_transform_from_the_future_is_refused(client: RosClient, robot: Go2RosRobot) -> None:
    tf = client.publisher(TFMessage, "/tf", TF_QOS)
    report = reported(
        robot,
        lambda: tf.publish(transforms(client, [("map", "odom")], ahead=1000.0)),
        "ahead of this computer's clock",
    )
    assert "/tf: ignored: map -> odom stamped" in report, report
