"""Over DDS: the mission node publishes each mission's planned path (nav_msgs/Path) and the known
objects (visualization_msgs/MarkerArray) for RViz, and a detection published on the Go2 robot's
detections topic becomes a known object: reported by the robot, in the markers, on the
dashboard's map. Go2RosRobot drives the in-process simulated driver; everything shares one DDS
context. Skipped without ROS unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "nav_msgs", "visualization_msgs")

from nav_msgs.msg import Path  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from shadowhound_interfaces.msg import Detection, DetectionArray  # noqa: E402
from visualization_msgs.msg import Marker, MarkerArray  # noqa: E402

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot  # noqa: E402
from shadowhound.robot.go2.robot import Go2RosConfig, Go2RosRobot  # noqa: E402
from shadowhound.ros.node import MissionNode  # noqa: E402
from shadowhound.ros.params import parse_parameters  # noqa: E402
from shadowhound.sim_driver.driver import SimDriver  # noqa: E402
from shadowhound.skills.context import robot_objects  # noqa: E402
from tests.ros.rosclient import RosClient, wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
GO2 = "/viz"  # the Go2 (driver, robot, mission node) namespace
SIM = "/vizsim"  # a mission node on the in-process simulator, with its map
LATCHED = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_rviz_test")
    yield c
    c.close()


def add(client: RosClient, *nodes: Any) -> None:
    for node in nodes:
        client.executor.add_node(node)


def remove(client: RosClient, *nodes: Any) -> None:
    for node in nodes:
        client.executor.remove_node(node)


@pytest.fixture(scope="module")
def go2(client: RosClient) -> Iterator[MissionNode]:
    # The driver's own detections off: this test publishes the only ones.
    driver = SimDriver(
        context=client.context, namespace=GO2, options={"odom_delay": 0.05, "detector": "none"}
    )
    add(client, *driver.nodes)
    # No map (map_topic ''): detections are known objects all the same.
    robot = Go2RosRobot(
        Go2RosConfig(namespace=GO2[1:], detections_topic="detections", map_topic=""),
        context=client.context,
    )
    wait_until(lambda: robot.last_state().connected, 30, "odometry from the in-process driver")
    settings = parse_parameters({"robot": "go2"}).agent_settings()  # as `shadowhound node`
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    node = MissionNode(agent, node_name="viz_agent", namespace=GO2, context=client.context)
    add(client, node)
    yield node
    remove(client, node, *driver.nodes)
    node.shutdown()
    node.destroy_node()
    robot.close()
    driver.close()
    driver.destroy_node()


@pytest.fixture(scope="module")
def sim(client: RosClient) -> Iterator[MissionNode]:
    config = ShadowHoundConfig()
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(config.sim, time_scale=0), settings=config))
    node = MissionNode(agent, node_name="viz_sim_agent", namespace=SIM, context=client.context)
    add(client, node)
    yield node
    remove(client, node)
    node.shutdown()
    node.destroy_node()


def objects_in(msg: MarkerArray) -> dict[str, tuple[float, float, float]]:
    """name -> (x, y, diameter), pairing each cylinder with the label of the same id."""
    labels = {m.id: m.text for m in msg.markers if m.type == Marker.TEXT_VIEW_FACING}
    return {
        labels[m.id]: (m.pose.position.x, m.pose.position.y, m.scale.x)
        for m in msg.markers
        if m.type == Marker.CYLINDER
    }


def test_the_planned_path_goes_around_the_ball_and_rviz_gets_every_object_seen(
    client: RosClient, sim: MissionNode
) -> None:
    markers = client.subscribe(MarkerArray, f"{SIM}/known_objects", LATCHED)
    paths = client.subscribe(Path, f"{SIM}/planned_path", LATCHED)
    result = sim.agent.execute_mission("go to x=4, y=0")
    assert result.success, result.response
    # The objects the robot saw on the way (planning looks first, every leg looks again).
    seen = {o.name for o in robot_objects(sim.agent.robot)}
    assert {"red ball", "blue box"} <= seen, seen
    shown = markers.wait_for(lambda m: set(objects_in(m)) == seen, 10, "the objects seen")
    assert shown.markers[0].action == Marker.DELETEALL  # nothing stale is left in RViz
    assert shown.markers[1].header.frame_id == "odom"
    ball = objects_in(shown)["red ball"]
    assert ball[:2] == (3.0, 0.0) and math.isclose(ball[2], 0.4, abs_tol=0.05)
    path = paths.wait_for(lambda m: len(m.poses) >= 2, 10, "the planned path")
    points = [(p.pose.position.x, p.pose.position.y) for p in path.poses]
    assert path.header.frame_id == "odom"
    assert points[0] == (0.0, 0.0) and points[-1] == (4.0, 0.0)
    assert max(abs(y) for _, y in points) > 0.3  # around the red ball at (3, 0)
    first = path.poses[0].pose.orientation  # each pose faces along its leg
    x1, y1 = points[1]
    assert math.isclose(2 * math.atan2(first.z, first.w), math.atan2(y1, x1), abs_tol=1e-6)

    late = client.subscribe(Path, f"{SIM}/planned_path", LATCHED)  # RViz started afterwards
    assert len(late.wait_for(lambda m: True, 10, "the latched path").poses) == len(points)


def test_a_published_detection_becomes_a_known_object_everywhere(
    client: RosClient, go2: MissionNode
) -> None:
    markers = client.subscribe(MarkerArray, f"{GO2}/known_objects", LATCHED)
    paths = client.subscribe(Path, f"{GO2}/planned_path", LATCHED)
    detections = client.publisher(DetectionArray, f"{GO2}/detections")
    robot = go2.agent.robot
    assert robot_objects(robot) == ()  # no map, nothing detected yet

    # Face +y first, so a body-frame detection must be turned into the odometry frame.
    result = go2.agent.execute_mission("turn left 90 degrees")
    assert result.success, result.response
    path = paths.wait_for(lambda m: len(m.poses) >= 1, 10, "the planned path")
    assert [(p.pose.position.x, p.pose.position.y) for p in path.poses] == [(0.0, 0.0)]
    wait_until(lambda: detections.get_subscription_count() > 0, 10, "the detections subscriber")

    msg = DetectionArray()
    msg.header.frame_id = "base_link"
    msg.header.stamp = client.node.get_clock().now().to_msg()
    ahead = Detection(label="charging dock", confidence=0.8, radius=0.3)
    ahead.position.x = 1.5  # 1.5 m in front of the robot
    fixed = Detection(label="blue box", confidence=0.6)
    fixed.header.frame_id = "odom"
    fixed.position.x, fixed.position.y = 2.5, 2.0
    lost = Detection(label="cup", confidence=0.9)
    lost.header.frame_id = "camera_optical"  # not a frame the robot can place: dropped
    msg.detections = [ahead, fixed, lost]
    detections.publish(msg)

    known = wait_until(
        lambda: {o.name: o for o in robot_objects(robot)} or None,
        10,
        "the detections to become known objects",
    )
    assert set(known) == {"charging dock", "blue box"}
    dock = known["charging dock"]
    assert math.isclose(dock.x, 0.0, abs_tol=0.05) and math.isclose(dock.y, 1.5, abs_tol=0.05)
    assert math.isclose(dock.radius, 0.3, rel_tol=1e-6)  # float32 on the wire
    assert math.isclose(dock.confidence, 0.8, rel_tol=1e-6)
    assert (known["blue box"].x, known["blue box"].y, known["blue box"].radius) == (2.5, 2.0, 0.25)

    shown = markers.wait_for(
        lambda m: set(objects_in(m)) == {"charging dock", "blue box"}, 10, "the detections in RViz"
    )
    assert math.isclose(objects_in(shown)["charging dock"][1], 1.5, abs_tol=0.05)

    from fastapi.testclient import TestClient

    from shadowhound.web import create_app

    with TestClient(create_app(go2.agent), base_url="http://127.0.0.1") as web:
        world = web.get("/api/map").json()
    assert world["grid"] is None  # no map on this robot: the objects are drawn all the same
    assert {o["name"] for o in world["objects"]} == {"charging dock", "blue box"}
