"""Go2RosRobot against the simulated driver, both in this process (one DDS context), plus the
driver's fault messages and its command line. Skipped without rclpy or go2_interfaces unless
SHADOWHOUND_REQUIRE_ROS=1 (then it fails)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Iterator
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces")

from geometry_msgs.msg import Twist  # noqa: E402
from go2_interfaces.msg import WebRtcReq  # noqa: E402
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from shadowhound.robot.base import RobotError  # noqa: E402
from shadowhound.robot.go2.robot import Go2RosConfig, Go2RosRobot  # noqa: E402
from shadowhound.sim_driver.driver import Faults, SimDriver  # noqa: E402
from shadowhound.state import Posture  # noqa: E402
from tests.ros.rosclient import ROOT, Inbox, RosClient, wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
NS = "/inproc"


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_robot_test")
    yield c
    c.close()


@pytest.fixture(scope="module")
def driver(client: RosClient) -> Iterator[SimDriver]:
    d = SimDriver(
        context=client.context, namespace=NS, options={"posture_seconds": 0.5, "odom_delay": 0.2}
    )
    for node in d.nodes:  # the driver and its twist_mux-like relay
        client.executor.add_node(node)
    yield d
    for node in d.nodes:
        client.executor.remove_node(node)
    d.close()
    d.destroy_node()


@pytest.fixture(scope="module")
def robot(client: RosClient, driver: SimDriver) -> Iterator[Go2RosRobot]:
    r = Go2RosRobot(Go2RosConfig(namespace=NS[1:]), context=client.context)
    wait_until(lambda: r.last_state().connected, 30, "odometry from the in-process driver")
    yield r
    r.close()


def api_ids(requests: Inbox, mark: int = 0) -> list[int]:
    return [json.loads(m.data)["api_id"] for m in requests.since(mark)]


def test_state_camera_caps_keep_alive_and_stop_move(
    client: RosClient, driver: SimDriver, robot: Go2RosRobot
) -> None:
    twists = client.subscribe(Twist, f"{NS}/cmd_vel")
    requests = client.subscribe(String, f"{NS}/sim_driver/requests")
    wait_until(lambda: requests.subscription.get_publisher_count() > 0, 10, "the driver")
    state = robot.get_state()
    assert state.connected and state.posture is Posture.STANDING
    assert state.battery is None  # go2_ros2_sdk publishes no battery level: unknown
    frame = wait_until(robot.get_camera_frame, 10, "a camera frame")
    assert (frame.encoding, frame.width, frame.height) == ("rgb8", 160, 120)
    robot.send_velocity(5.0, 0.0, 9.0)  # beyond the Go2 caps (1 m/s, 2 rad/s)
    try:
        first = twists.wait_for(lambda m: m.linear.x > 0, 5, "a Twist")
        assert (first.linear.x, first.angular.z) == (1.0, 2.0)
        # The relay subscribes cmd_vel, so that is where velocity goes (through twist_mux).
        assert robot.velocity_topic == f"{NS}/cmd_vel"
        # No further calls: the keep-alive repeats the command (a Move lapses after ~1 s).
        wait_until(lambda: sum(m.linear.x == 1.0 for m in twists.items) >= 4, 5, "keep-alive")
        wait_until(lambda: driver.truth().moving, 10, "the true robot to walk")
    finally:
        mark, sent = twists.mark(), requests.mark()
        robot.stop()
    requests.wait_for(lambda m: json.loads(m.data)["api_id"] == 1003, 5, "StopMove", sent)
    wait_until(lambda: not driver.truth().moving, 10, "the true robot to stop")
    # The driver drops zero Twists: a stop is StopMove, and no zero Twist is ever sent.
    assert all(m.linear.x == 1.0 for m in twists.items), [m.linear.x for m in twists.items]
    assert all(m.linear.x == 1.0 for m in twists.since(mark))  # the keep-alive went quiet
    robot.send_velocity(0.0, 0.0, 0.0)  # already stopped: nothing more to send
    assert api_ids(requests, sent).count(1003) == 1


def test_postures_are_read_from_go2_states_and_sent_only_when_needed(
    client: RosClient, driver: SimDriver, robot: Go2RosRobot
) -> None:
    requests = client.subscribe(String, f"{NS}/sim_driver/requests")
    wait_until(lambda: requests.subscription.get_publisher_count() > 0, 10, "the driver")
    robot.set_posture(Posture.STANDING)  # standing already: no StandUp, no BalanceStand
    robot.set_posture(Posture.LYING)  # returns once go2_states shows the posture reached
    assert driver.truth().posture is Posture.LYING and not driver.truth().changing
    assert robot.get_state().posture is Posture.LYING
    with pytest.raises(RobotError, match="cannot perform hello while the robot is lying"):
        robot.perform("hello")
    robot.set_posture(Posture.STANDING)
    truth = driver.truth()
    assert truth.posture is Posture.STANDING and truth.mode in (1, 3)  # balanced: can walk
    wait_until(lambda: len(api_ids(requests)) >= 3, 5, "the driver's records")
    assert api_ids(requests) == [1005, 1004, 1002]  # StandDown; StandUp, BalanceStand
    robot.set_posture(Posture.SITTING)
    robot.set_posture(Posture.STANDING)  # RiseSit ends balanced: no BalanceStand after it
    assert driver.truth().mode in (1, 3)
    # Standing with locked joints (someone sent StandUp): "stand up" only balances.
    client.publisher(WebRtcReq, f"{NS}/webrtc_req").publish(
        WebRtcReq(id=0, topic="rt/api/sport/request", api_id=1004, parameter="", priority=0)
    )
    wait_until(
        lambda: driver.truth().mode == 6 and not driver.truth().changing,
        10,
        "the robot standing locked",
    )
    # go2_states come as late as odometry: wait until the robot, too, sees the joints locked.
    wait_until(lambda: not robot.walking_mode, 5, "go2_states showing the joints locked")
    assert robot.get_state().posture is Posture.STANDING
    robot.set_posture(Posture.STANDING)
    assert driver.truth().mode in (1, 3)
    wait_until(lambda: len(api_ids(requests)) >= 7, 5, "the driver's records")
    assert api_ids(requests)[3:] == [1009, 1010, 1004, 1002]


def test_a_robot_that_reports_damping_after_stand_up_stands_and_walks_without_ignored_moves(
    client: RosClient,
) -> None:
    """Issue 23: some firmware reports Damping (7) after StandUp. Standing is judged by the body
    height, BalanceStand follows, and the walk starts only once the robot walks."""
    damped = SimDriver(
        context=client.context,
        namespace="/damped",
        options={"posture_seconds": 0.5, "start_posture": "lying", "stand_up_mode": 7},
    )
    for node in damped.nodes:
        client.executor.add_node(node)
    requests = client.subscribe(String, "/damped/sim_driver/requests")
    robot = Go2RosRobot(
        Go2RosConfig(namespace="damped", node_name="shadowhound_go2_damped"),
        context=client.context,
    )
    try:
        wait_until(lambda: robot.last_state().connected, 30, "odometry from the damped driver")
        wait_until(lambda: requests.subscription.get_publisher_count() > 0, 10, "the driver")
        robot.set_posture(Posture.STANDING)
        truth = damped.truth()
        assert truth.posture is Posture.STANDING and truth.mode in (1, 3), truth
        wait_until(lambda: len(api_ids(requests)) >= 2, 5, "the driver's records")
        assert api_ids(requests) == [1004, 1002]  # StandUp, then BalanceStand
        robot.send_velocity(0.3, 0.0, 0.0)
        try:
            wait_until(lambda: damped.truth().moving, 10, "the true robot to walk")
        finally:
            robot.stop()
        assert damped.truth().moves_ignored == 0
    finally:
        robot.close()
        for node in damped.nodes:
            client.executor.remove_node(node)
        damped.close()
        damped.destroy_node()


def test_a_walk_on_a_robot_standing_with_locked_joints_balances_it_first(
    client: RosClient, driver: SimDriver, robot: Go2RosRobot
) -> None:
    """Someone else's StandUp leaves the robot standing with locked joints (mode 6): a walk
    sends BalanceStand first and starts once the robot walks, so no Move is ignored."""
    requests = client.subscribe(String, f"{NS}/sim_driver/requests")
    webrtc = client.publisher(WebRtcReq, f"{NS}/webrtc_req")
    wait_until(lambda: requests.subscription.get_publisher_count() > 0, 10, "the driver")
    wait_until(lambda: webrtc.get_subscription_count() > 0, 10, "the driver's webrtc_req")
    robot.set_posture(Posture.STANDING)
    webrtc.publish(
        WebRtcReq(id=0, topic="rt/api/sport/request", api_id=1004, parameter="", priority=0)
    )
    wait_until(
        lambda: driver.truth().mode == 6 and not driver.truth().changing,
        10,
        "the robot standing locked",
    )
    wait_until(lambda: robot.joints_held, 5, "go2_states to show it to the robot")
    ignored, mark = driver.truth().moves_ignored, requests.mark()
    robot.send_velocity(0.3, 0.0, 0.0)
    try:
        wait_until(lambda: driver.truth().moving, 10, "the true robot to walk")
    finally:
        robot.stop()
    wait_until(lambda: not driver.truth().moving, 10, "the true robot to stop")
    assert driver.truth().moves_ignored == ignored
    assert 1002 in api_ids(requests, mark)


def test_firmware_tricks_are_refused_unless_enabled(robot: Go2RosRobot) -> None:
    with pytest.raises(
        RobotError,
        match=r"backflip \(api id 1044\) runs only on Go2 firmware "
        "that has it",
    ):
        robot.perform("backflip")


def test_enabled_firmware_tricks_switch_to_the_ai_motion_mode_first(
    client: RosClient, driver: SimDriver, robot: Go2RosRobot
) -> None:
    requests = client.subscribe(String, f"{NS}/sim_driver/requests")
    enabled = Go2RosRobot(
        Go2RosConfig(namespace=NS[1:], firmware_tricks=True, node_name="shadowhound_go2_firmware"),
        context=client.context,
    )
    try:
        wait_until(lambda: enabled.last_state().connected, 30, "odometry")
        assert not driver.truth().ai_mode
        enabled.perform("moonwalk")  # 1305: only in the "ai" motion mode
        assert driver.truth().ai_mode
        records = [json.loads(m.data) for m in requests.items]
        moonwalk = [r for r in records if r["api_id"] == 1305]
        assert moonwalk and moonwalk[0]["accepted"], records
    finally:
        enabled.close()


def test_the_estop_sends_stop_move_and_refuses_motion_until_released(
    client: RosClient, driver: SimDriver, robot: Go2RosRobot
) -> None:
    twists = client.subscribe(Twist, f"{NS}/cmd_vel")
    requests = client.subscribe(String, f"{NS}/sim_driver/requests")
    wait_until(lambda: requests.subscription.get_publisher_count() > 0, 10, "the driver")
    robot.emergency_stop()
    try:
        requests.wait_for(lambda m: json.loads(m.data)["api_id"] == 1003, 5, "StopMove")
        assert robot.get_state().estopped
        robot.send_velocity(0.3, 0.0, 0.0)  # ignored, like the simulator
        with pytest.raises(RobotError, match="e-stop is latched"):
            robot.set_posture(Posture.SITTING)
        assert twists.items == []
    finally:
        robot.release_estop()
    robot.send_velocity(0.1, 0.0, 0.0)
    robot.stop()
    twists.wait_for(lambda m: m.linear.x == 0.1, 5, "motion after the release")


_SPEEDS = st.sampled_from([0.0, 0.0, 0.2, -0.3])
_OPERATIONS = st.lists(
    st.one_of(
        st.tuples(st.just("move"), _SPEEDS, _SPEEDS, _SPEEDS),
        st.just(("zero",)),
        st.just(("stop",)),
        st.just(("estop",)),
    ),
    min_size=1,
    max_size=6,
)


_LISTENING: dict[int, tuple[Any, Any]] = {}


def _listening(client: RosClient, robot: Go2RosRobot) -> tuple[Any, Any]:
    """This module's readers of the robot's cmd_vel and webrtc_req, made once and matched on
    both sides of DDS (the robot's writers see them, they see the robot's): a request the
    robot sends after this is read, whichever side discovered the other last."""
    if id(robot) not in _LISTENING:
        request_pub = robot._request_pub
        twist_pub = robot._twist_pubs[robot._discover_velocity_topic()]
        had = request_pub.get_subscription_count(), twist_pub.get_subscription_count()
        twists = client.subscribe(Twist, f"{NS}/cmd_vel")
        requests = client.subscribe(WebRtcReq, f"{NS}/webrtc_req")
        wait_until(
            lambda: (
                requests.subscription.get_publisher_count() > 0
                and twists.subscription.get_publisher_count() > 0
                and request_pub.get_subscription_count() > had[0]
                and twist_pub.get_subscription_count() > had[1]
            ),
            10,
            "the robot's cmd_vel and webrtc_req writers and these readers to match",
        )
        _LISTENING[id(robot)] = (twists, requests)
    return _LISTENING[id(robot)]


@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(operations=_OPERATIONS)
def test_every_stop_is_a_stop_move_and_no_zero_twist_is_ever_sent(
    client: RosClient, driver: SimDriver, robot: Go2RosRobot, operations: list[tuple[object, ...]]
) -> None:
    """The whole kind: whatever the sequence of commands, each stop (stop, e-stop, a zero
    command after motion) reaches the driver as StopMove, and no all-zero Twist goes out
    (the driver would drop it and the robot keep walking)."""
    twists, requests = _listening(client, robot)
    seen_twists, seen_requests = len(twists.items), len(requests.items)
    expected, moving = 0, False
    for op in [*operations, ("stop",)]:
        if op[0] == "move":
            values = (float(op[1]), float(op[2]), float(op[3]))  # type: ignore[arg-type]
            robot.send_velocity(*values)
            expected += moving and not any(values)
            moving = any(values)
        elif op[0] == "zero":
            robot.send_velocity(0.0, 0.0, 0.0)
            expected += moving
            moving = False
        elif op[0] == "stop":
            robot.stop()
            expected, moving = expected + 1, False
        else:
            robot.emergency_stop()
            robot.release_estop()
            expected, moving = expected + 1, False

    def stops() -> int:
        return sum(m.api_id == 1003 for m in requests.items[seen_requests:])

    wait_until(lambda: stops() >= expected, 10, f"{expected} StopMoves")
    assert stops() == expected
    assert all(m.linear.x or m.linear.y or m.angular.z for m in twists.items[seen_twists:])
    wait_until(lambda: not driver.truth().moving, 10, "the true robot to stop")


def _tf_message(edges: list[tuple[str, str]], sec: int) -> object:
    """Transforms stamped `sec` seconds after the client's clock now (ROS time)."""
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage

    msg = TFMessage()
    for parent, child in edges:
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = parent, child
        t.header.stamp.sec = sec + int(time.time())
        t.transform.translation.x = 0.1
        t.transform.rotation.w = 1.0
        msg.transforms.append(t)
    return msg


# What robot_state_publisher sends about a Go2's body on /tf at 50 Hz: 30 links nobody reads.
_LINKS = [
    (parent, child)
    for leg in ("FL", "FR", "RL", "RR")
    for parent, child in zip(
        ("base_link", f"{leg}_hip", f"{leg}_thigh", f"{leg}_calf", f"{leg}_calf", f"{leg}_foot"),
        (
            f"{leg}_hip",
            f"{leg}_thigh",
            f"{leg}_calf",
            f"{leg}_calflower",
            f"{leg}_foot",
            f"{leg}_toe",
        ),
        strict=True,
    )
] + [
    ("base_link", link)
    for link in ("Head_upper", "Head_lower", "imu", "radar", "front_camera", "base_footprint")
]


def test_tf_feeds_the_frames_tree_only_with_the_edges_it_is_asked_about(
    client: RosClient,
) -> None:
    """A /tf message full of the body's links (robot_state_publisher's, 50 Hz) leaves them out
    of the robot's frames tree, before its state lock; SLAM's map -> odom goes in (the world
    becomes the map), and so does odom -> base_link, where a map -> odom jump is measured."""
    assert len(_LINKS) == 30
    lonely = Go2RosRobot(
        Go2RosConfig(namespace="tf_only", node_name="shadowhound_go2_tf"), context=client.context
    )
    try:
        lonely._on_tf_static(_tf_message(_LINKS, 0))
        lonely._on_tf(_tf_message([*_LINKS, ("map", "odom"), ("odom", "base_link")], 0))
        lonely._on_tf(_tf_message(_LINKS, 1))
        assert lonely.world_frame == "map"
        assert lonely._tf.frames() == {"map", "odom", "base_link"}
    finally:
        lonely.close()


def test_without_a_driver_commands_time_out_and_motion_is_refused(client: RosClient) -> None:
    lonely = Go2RosRobot(
        Go2RosConfig(namespace="nobody", command_timeout=0.3), context=client.context
    )
    try:
        state = lonely.get_state()  # at rest: the last (here: no) state, marked disconnected
        assert state.connected is False
        with pytest.raises(RobotError, match="no odometry received on /nobody/odom"):
            lonely.send_velocity(0.2, 0.0, 0.0)
        with pytest.raises(
            RobotError,
            match="cannot tell the robot's posture: /nobody/go2_states shows no messages",
        ):
            lonely.set_posture(Posture.SITTING)
    finally:
        lonely.close()


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("{}", Faults()),
        ('{"odom": false, "delay_ms": 250}', Faults(odom=False, delay=0.25)),
        ('{"drop_commands": true}', Faults(drop_commands=True)),
        ('{"stall_ms": 400, "after_deg": 75}', Faults(stall=0.4, after_deg=75.0)),
    ],
)
def test_fault_messages(text: str, expected: Faults) -> None:
    assert Faults.from_json(text) == expected


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('{"lidar": false}', "unknown fault(s) ['lidar']"),
        ('{"odom": "no"}', "take true or false"),
        ('{"delay_ms": -5}', "delay_ms must be a number of milliseconds in 0..10000"),
        ('{"stall_ms": 6000}', "stall_ms must be a number of milliseconds in 0..5000"),
        ("[1]", "must be a JSON object"),
    ],
)
def test_bad_fault_messages_are_explained(text: str, message: str) -> None:
    with pytest.raises(ValueError) as info:
        Faults.from_json(text)
    assert message in str(info.value)


def test_the_driver_rejects_bad_parameters_with_exit_code_2() -> None:
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "shadowhound",
            "sim-driver",
            "--ros-args",
            "-p",
            "odom_rate_hz:=0",
            "-p",
            "camera_width:=wide",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert done.returncode == 2, done.stderr
    assert "odom_rate_hz must be in 1..200, got 0" in done.stderr
    assert "camera_width must be an integer, got str 'wide'" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_go2_implements_the_whole_robot_protocol(robot: Go2RosRobot) -> None:
    """A real robot's clock is the wall clock (the watchdog guards it); its world model is the
    driver's map (one object for its life), its known objects what it was told."""
    from shadowhound.robot.base import Robot
    from shadowhound.world import Belief

    assert isinstance(robot, Robot)
    assert robot.description == f"Go2 over ROS (namespace {NS})"  # what a dashboard says
    assert robot.realtime and robot.time_scale == 1.0
    belief = robot.belief()
    assert belief is None or (isinstance(belief, Belief) and robot.belief() is belief)
    assert robot.known_objects() == ()
    assert robot.last_state().stamp >= 0.0


def test_a_large_map_is_read_off_the_odometry_thread(
    client: RosClient, driver: SimDriver, robot: Go2RosRobot
) -> None:
    """A 2000 x 2000 map takes seconds to read and inflate: odometry keeps arriving meanwhile
    (it once stalled on the same executor thread, and missions failed "no odometry")."""
    from shadowhound.robot.go2.world_msgs import MAP_QOS, grid_to_msg
    from shadowhound.robot.sim import sensors
    from shadowhound.world import OccupancyGrid

    big = OccupancyGrid(2000, 2000, 0.05, cells=bytearray(2000 * 2000))
    big.cells[1000 * 2000 + 1000] = 100  # something to inflate
    maps = client.publisher(type(grid_to_msg(big, "odom", None)), f"{NS}/map", MAP_QOS)
    wait_until(lambda: maps.get_subscription_count() > 0, 10, "the robot's map subscription")
    maps.publish(grid_to_msg(big, "odom", client.node.get_clock().now().to_msg()))
    stale = []

    def read() -> bool:
        if not robot.last_state().connected:
            stale.append(robot.last_state().stamp)
        belief = robot.belief()  # the grid is swapped in once inflated (Belief.replace_grid)
        return belief is not None and belief.grid.width == 2000

    wait_until(read, 120, "the large map to be read", interval=0.05)
    assert stale == [], f"odometry went stale {len(stale)} times while the map was read"
    # Back to the driver's own map for anything after.
    scene = sensors.scene_grid(driver.robots[0].sim.map_world)
    maps.publish(grid_to_msg(scene, "odom", client.node.get_clock().now().to_msg()))
