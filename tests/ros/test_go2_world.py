"""The Go2 robot's world over DDS: the sim driver's `map` and `scan` read into `belief()` and
`get_scan()`, a map's frame, origin and resolution respected, no map = no belief, and the
NavigateToPose client (`navigator()`) reporting a Nav2 failure in words. Driver and robot in
this process (one DDS context). Skipped without rclpy or the interface packages unless
SHADOWHOUND_REQUIRE_ROS=1."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "nav2_msgs")

from shadowhound.errors import RobotError  # noqa: E402
from shadowhound.robot.go2.robot import Go2RosConfig, Go2RosRobot  # noqa: E402
from shadowhound.robot.go2.world_msgs import MAP_QOS, grid_to_msg  # noqa: E402
from shadowhound.robot.navigator import NavStatus  # noqa: E402
from shadowhound.robot.sim.sensors import scene_grid  # noqa: E402
from shadowhound.sim_driver.driver import SimDriver  # noqa: E402
from shadowhound.state import Pose2D  # noqa: E402
from shadowhound.world import OCCUPIED, OccupancyGrid  # noqa: E402
from tests.ros.rosclient import RosClient, wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
NS = "/world"


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_world_test")
    yield c
    c.close()


@pytest.fixture(scope="module")
def driver(client: RosClient) -> Iterator[SimDriver]:
    d = SimDriver(context=client.context, namespace=NS, options={"camera_rate_hz": 0.0})
    for node in d.nodes:
        client.executor.add_node(node)
    yield d
    for node in d.nodes:
        client.executor.remove_node(node)
    d.close()
    d.destroy_node()


@pytest.fixture(scope="module")
def robot(client: RosClient, driver: SimDriver) -> Iterator[Go2RosRobot]:
    # Started after the driver published its map once: transient local still delivers it.
    r = Go2RosRobot(Go2RosConfig(namespace=NS[1:], camera_topic=""), context=client.context)
    wait_until(lambda: r.last_state().connected, 30, "odometry from the in-process driver")
    yield r
    r.close()


def test_the_drivers_map_becomes_the_belief(driver: SimDriver, robot: Go2RosRobot) -> None:
    belief = wait_until(robot.belief, 10, "the map")
    scene = scene_grid(driver.sim.map_world)
    grid = belief.grid
    assert (grid.width, grid.height, grid.resolution) == (scene.width, scene.height, 0.05)
    assert (grid.origin.x, grid.origin.y) == pytest.approx((scene.origin.x, scene.origin.y))
    assert grid.cells == scene.cells
    assert grid.value_at(3.0, 0.0) == OCCUPIED  # the red ball
    assert grid.value_at(1.0, 0.0) == 0
    # One world model for the robot's life (as the simulator's): what missions learn (scan
    # updates, sightings) stays until the next map message replaces the grid.
    assert robot.belief() is belief


def test_the_drivers_scan_is_the_simulators(driver: SimDriver, robot: Go2RosRobot) -> None:
    scan = wait_until(robot.get_scan, 10, "a scan")
    assert len(scan.ranges) == 360 and (scan.range_min, scan.range_max) == (0.1, 8.0)
    truth = driver.truth()
    assert math.hypot(scan.pose.x - truth.x, scan.pose.y - truth.y) < 0.05
    ahead = min(range(360), key=lambda i: abs(scan.angle_min + i * scan.angle_increment))
    # From the start pose, straight ahead is the red ball's surface: 3.0 - 0.2 m.
    assert scan.ranges[ahead] == pytest.approx(2.8, abs=0.02)


def test_a_maps_frame_origin_and_resolution_are_respected(client: RosClient) -> None:
    # A 10 cm map turned 90 degrees, its corner at (1, 2): cell (col 2, row 0) is occupied.
    grid = OccupancyGrid(4, 3, 0.1, Pose2D(1.0, 2.0, math.pi / 2), bytearray(12))
    grid.cells[2] = OCCUPIED
    publisher = client.publisher(
        type(grid_to_msg(grid, "odom", client.node.get_clock().now().to_msg())),
        "/turned/map",
        MAP_QOS,
    )
    publisher.publish(grid_to_msg(grid, "odom", client.node.get_clock().now().to_msg()))
    robot = Go2RosRobot(
        Go2RosConfig(namespace="turned", camera_topic="", nav2_action=""), context=client.context
    )
    try:
        belief = wait_until(robot.belief, 10, "the turned map")
        got = belief.grid
        assert (got.width, got.height, got.resolution) == (4, 3, pytest.approx(0.1))
        assert (got.origin.x, got.origin.y, got.origin.yaw) == pytest.approx(
            (1.0, 2.0, math.pi / 2)
        )
        # Column 2 runs along the origin's x axis, which points along the world's +y.
        assert got.value_at(1.0 - 0.05, 2.0 + 0.25) == OCCUPIED
        assert got.value_at(1.0 - 0.05, 2.0 + 0.15) == 0
        assert got.value_at(1.0 + 0.05, 2.0 + 0.25) == -1  # outside: unknown
        assert robot.navigator() is None  # nav2_action '' = no Nav2
    finally:
        robot.close()


def test_without_a_map_there_is_no_belief(client: RosClient) -> None:
    robot = Go2RosRobot(Go2RosConfig(namespace="nomap", camera_topic=""), context=client.context)
    try:
        time.sleep(1.0)  # long enough for a transient-local map, if one were there
        assert robot.belief() is None and robot.get_scan() is None
    finally:
        robot.close()


def test_a_nav2_failure_comes_back_in_words(robot: Go2RosRobot) -> None:
    navigator = robot.navigator()
    assert navigator is not None and navigator.ready(10.0)
    goal = navigator.navigate(2.5, 2.0, 0.0)  # the blue box
    report = wait_until(lambda: goal.report().done and goal.report(), 30, "the goal to end")
    assert report.status is NavStatus.FAILED
    assert report.message.startswith(
        "the goal is occupied on the costmap (inside an obstacle or its inflation) (Nav2 error "
        "code 206): the goal (2.50, 2.00) is inside the blue box's clearance"
    ), report.message


def test_stop_cancels_a_running_nav2_goal(driver: SimDriver, robot: Go2RosRobot) -> None:
    navigator = robot.navigator()
    assert navigator is not None and navigator.ready(10.0)
    start = driver.truth()
    goal = navigator.navigate(start.x - 1.0, start.y, math.pi)
    wait_until(
        lambda: goal.report().status is NavStatus.RUNNING and driver.truth().moving,
        20,
        "the goal to drive the robot",
    )
    robot.stop()
    report = wait_until(lambda: goal.report().done and goal.report(), 10, "the goal to end")
    assert report.status is NavStatus.CANCELED
    wait_until(lambda: not driver.truth().moving, 5, "the robot to stop")
    time.sleep(1.0)
    assert not driver.truth().moving  # nothing drives it on


@settings(
    max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(delay=st.floats(0.0, 1.2))
def test_a_stop_at_any_moment_ends_the_goal_and_nothing_drives_on(
    driver: SimDriver, robot: Go2RosRobot, delay: float
) -> None:
    """Whenever the stop comes (before Nav2 accepted the goal, while it turns, while it walks),
    the goal ends cancelled and the robot stays still: a stop no goal outlives."""
    navigator = robot.navigator()
    assert navigator is not None and navigator.ready(10.0)
    wait_until(lambda: not driver.truth().moving, 10, "the robot still before the goal")
    start = driver.truth()
    goal = navigator.navigate(start.x + (-1.5 if start.x > 0 else 1.5), start.y, 0.0)
    time.sleep(delay)
    robot.stop()
    report = wait_until(lambda: goal.report().done and goal.report(), 10, "the goal to end")
    assert report.status is NavStatus.CANCELED, report
    wait_until(lambda: not driver.truth().moving, 5, "the robot to stop")
    still = driver.truth()
    time.sleep(0.5)
    after = driver.truth()
    assert math.hypot(after.x - still.x, after.y - still.y) < 1e-3
    assert driver.robots[0].navigator is not None
    assert not driver.robots[0].navigator.truth()["active"]


def test_a_go2_without_a_speech_topic_has_no_voice_and_says_so(client: RosClient) -> None:
    robot = Go2RosRobot(
        Go2RosConfig(namespace="mute", camera_topic="", nav2_action="", speech_topic=""),
        context=client.context,
    )
    try:
        with pytest.raises(RobotError, match="no voice: speech_topic is ''"):
            robot.say("hello")
    finally:
        robot.close()
