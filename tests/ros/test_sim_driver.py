"""`shadowhound sim-driver` behaves as go2_ros2_sdk really does, judged by its ground truth.

The driver runs as its own process (as a user runs it) and this process talks to it over real
DDS on loopback: Twists on cmd_vel_out (or cmd_vel through the relay), WebRtcReq sport
requests; it reads odom, go2_states, battery_state, and the truth (sim_driver/truth: the true
pose, velocity, posture and counts of what the robot received), which no client of a real
driver has. Skipped without rclpy or go2_interfaces unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import bisect
import json
import math
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "go2_interfaces")

from geometry_msgs.msg import Twist  # noqa: E402
from go2_interfaces.msg import Go2State, WebRtcReq  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from sensor_msgs.msg import BatteryState  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from shadowhound.robot.go2 import api as go2_api  # noqa: E402
from shadowhound.robot.go2.api import SportMode  # noqa: E402
from shadowhound.state import Posture  # noqa: E402
from tests.ros.rosclient import (  # noqa: E402
    ROOT,
    NodeProcess,
    RosClient,
    wait_matched,
    wait_until,
)

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
MOVE_TIMEOUT, ODOM_DELAY, POSTURE_SECONDS = 1.5, 0.5, 1.0
DRIVER = (
    "--move-timeout",
    str(MOVE_TIMEOUT),
    "--odom-delay",
    str(ODOM_DELAY),
    "--posture-seconds",
    str(POSTURE_SECONDS),
    "--battery",
    "50",
    "--battery-drain",
    "0.1",
    "--camera-rate-hz",
    "0",
)
TIMEOUT = 20.0
PING_API_ID = 0  # no sport command: a readiness ping the driver drops and records
Truth = dict[str, Any]


class Driver:
    """One simulated robot's topics, seen from the test client; `base` is its name prefix."""

    def __init__(self, client: RosClient, base: str = "") -> None:
        self.client, self.base = client, base
        self.odom = client.subscribe(Odometry, f"{base}/odom")
        self.states = client.subscribe(Go2State, f"{base}/go2_states")
        self.records = client.subscribe(String, f"{base}/sim_driver/requests")
        self.cmd_vel_out = client.publisher(Twist, f"{base}/cmd_vel_out")
        self.webrtc = client.publisher(WebRtcReq, f"{base}/webrtc_req")  # the last writer
        self.truths = client.subscribe(String, f"{base}/sim_driver/truth")  # last reader: 50 Hz

    def wait_ready(self, process: NodeProcess) -> None:
        """Until the driver and this client have matched every topic both ways."""

        def ping() -> Callable[[], bool]:  # a request the driver drops (not JSON) and records
            mark = self.records.mark()
            self.request(PING_API_ID, parameter="{")
            return lambda: (
                PING_API_ID in [json.loads(m.data)["api_id"] for m in self.records.since(mark)]
            )

        wait_matched(
            self.client,
            f"the simulated driver under {self.base or '/'}",
            [self.odom, self.states, self.records, self.truths],
            [self.cmd_vel_out, self.webrtc],
            ping=ping,
            alive=process.check_alive,
            timeout=TIMEOUT,
        )

    def close(self) -> None:
        self.client.destroy(
            self.odom, self.states, self.records, self.cmd_vel_out, self.webrtc, self.truths
        )

    def truth(self) -> Truth:
        return json.loads(self.truths.latest().data)

    def truths_since(self, mark: int) -> list[Truth]:
        return [json.loads(m.data) for m in self.truths.since(mark)]

    def wait_truth(
        self,
        match: Callable[[Truth], bool],
        what: str,
        mark: int | None = None,
        timeout: float = TIMEOUT,
    ) -> Truth:
        start = self.truths.mark() if mark is None else mark
        msg = self.truths.wait_for(lambda m: match(json.loads(m.data)), timeout, what, start)
        return json.loads(msg.data)

    def twist(self, x: float = 0.0, y: float = 0.0, z: float = 0.0, publisher: Any = None) -> None:
        msg = Twist()
        msg.linear.x, msg.linear.y, msg.angular.z = x, y, z
        (publisher or self.cmd_vel_out).publish(msg)

    def walk(self, x: float, seconds: float, publisher: Any = None) -> None:
        """Renew a Move at 10 Hz, as a controller does."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.twist(x, publisher=publisher)
            time.sleep(0.1)

    def request(self, api_id: int, parameter: str = "", topic: str = go2_api.SPORT_TOPIC) -> None:
        self.webrtc.publish(
            WebRtcReq(id=0, topic=topic, api_id=api_id, parameter=parameter, priority=0)
        )

    def record(self, api_id: int, mark: int) -> dict[str, Any]:
        msg = self.records.wait_for(
            lambda m: json.loads(m.data)["api_id"] == api_id,
            TIMEOUT,
            f"the driver's record of api id {api_id}",
            mark,
        )
        return dict(json.loads(msg.data))

    def rest(self) -> Truth:
        """StopMove, then the truth once it has arrived (through the 10 Hz queue: a Twist
        sent meanwhile would overtake it) and the robot is standing balanced and still."""
        stops = self.truth()["stop_moves"]
        self.request(go2_api.STOP_MOVE)
        return self.wait_truth(
            lambda t: (
                t["stop_moves"] > stops
                and not t["moving"]
                and not t["changing"]
                and t["mode"] == SportMode.BALANCE_STAND
            ),
            "the robot at rest",
        )


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_sim_driver_test")
    yield c
    c.close()


@pytest.fixture(scope="module")
def driver(client: RosClient) -> Iterator[Driver]:
    process = NodeProcess(command="sim-driver", options=DRIVER)
    robot = Driver(client)
    try:
        robot.wait_ready(process)
        yield robot
        process.check_alive()
    finally:
        code = process.stop(signal.SIGTERM)
    assert code == 0, process.output()[-2000:]


def interpolate(series: list[tuple[float, float]], at: float) -> float:
    """Linear interpolation in a time-sorted [(t, value)] series."""
    times = [t for t, _v in series]
    i = bisect.bisect_left(times, at)
    assert 0 < i < len(series), f"{at} is outside the truth recorded"
    (t0, v0), (t1, v1) = series[i - 1], series[i]
    return v0 + (v1 - v0) * (at - t0) / (t1 - t0)


def test_a_zero_twist_is_dropped_and_the_move_runs_on_until_it_lapses(driver: Driver) -> None:
    before = driver.rest()
    mark = driver.truths.mark()
    driver.twist(0.3)
    moved = driver.wait_truth(lambda t: t["moves"] == before["moves"] + 1, "the Move", mark)
    driver.wait_truth(lambda t: t["vx"] > 0.29, "walking at 0.3 m/s", mark)
    driver.twist(0.0)  # what a controller sends to "stop": go2_ros2_sdk drops it
    dropped = driver.wait_truth(
        lambda t: t["twists_dropped"] == before["twists_dropped"] + 1,
        "the zero Twist to arrive",
        mark,
    )
    assert dropped["moving"] and dropped["vx"] > 0.29 and dropped["moves"] == moved["moves"]
    lapsed = driver.wait_truth(
        lambda t: t["moves_lapsed"] == before["moves_lapsed"] + 1, "the Move to lapse", mark
    )
    # It ran on for the whole move timeout after the last Move (truth sampled at 50 Hz).
    assert lapsed["mono"] - moved["mono"] >= MOVE_TIMEOUT - 0.05
    assert all(
        t["moving"]
        for t in driver.truths_since(mark)
        if dropped["mono"] <= t["mono"] < lapsed["mono"]
    )
    braking = driver.truths.mark()
    still = driver.wait_truth(lambda t: not t["moving"], "the robot to brake", braking)
    assert still["mono"] > lapsed["mono"]
    assert still["stop_moves"] == before["stop_moves"]  # the lapse stopped it, nothing else
    # A Twist that rounds to zero is not dropped: it is a Move of zero.
    driver.twist(0.004)
    tiny = driver.wait_truth(lambda t: t["moves"] == still["moves"] + 1, "the tiny Move", braking)
    assert tiny["twists_dropped"] == dropped["twists_dropped"] and not tiny["moving"]


def test_stop_move_stops_at_once_without_waiting_for_the_lapse(driver: Driver) -> None:
    before = driver.rest()
    mark, records = driver.truths.mark(), driver.records.mark()
    driver.walk(0.4, 1.0)
    assert driver.truth()["vx"] > 0.39
    driver.request(go2_api.STOP_MOVE)
    driver.wait_truth(lambda t: t["stop_moves"] == before["stop_moves"] + 1, "StopMove", mark)
    still = driver.wait_truth(lambda t: not t["moving"], "the robot to stop", driver.truths.mark())
    assert still["moves_lapsed"] == before["moves_lapsed"]  # stopped long before any lapse
    record = driver.record(go2_api.STOP_MOVE, records)
    assert record["accepted"] and record["sent"] >= record["mono"]  # through the 10 Hz queue


def test_odometry_is_the_truth_of_odom_delay_ago_and_has_no_twist(driver: Driver) -> None:
    driver.rest()
    truth_mark, odom_mark, state_mark = (
        driver.truths.mark(),
        driver.odom.mark(),
        driver.states.mark(),
    )
    driver.walk(0.5, 2.5)
    walking = driver.truth()
    states = driver.states.since(state_mark)
    driver.rest()
    truths = driver.truths_since(truth_mark)
    xs = [(t["stamp"], t["x"]) for t in truths]
    steady = [t["stamp"] for t in truths if t["vx"] > 0.49]
    odom = [
        m for m in driver.odom.since(odom_mark) if steady[0] + ODOM_DELAY < stamp_of(m) < steady[-1]
    ]
    assert len(odom) >= 10
    for msg in odom:
        stamp, x = stamp_of(msg), msg.pose.pose.position.x
        assert abs(x - interpolate(xs, stamp - ODOM_DELAY)) < 0.02  # the pose of 0.5 s before
        assert interpolate(xs, stamp) - x > 0.2  # ... not the pose at its stamp
    twists = [m.twist.twist for m in driver.odom.since(odom_mark)]
    assert all((t.linear.x, t.linear.y, t.angular.z) == (0.0, 0.0, 0.0) for t in twists)
    # go2_states carries the velocity (odom frame) and the body height from the truth.
    assert walking["mode"] == SportMode.LOCOMOTION
    assert any(
        s.mode == SportMode.LOCOMOTION
        and abs(s.velocity[0] - 0.5) < 0.01
        and math.isclose(s.body_height, 0.32, abs_tol=1e-6)
        for s in states
    )


def stamp_of(msg: Any) -> float:
    return float(msg.header.stamp.sec + msg.header.stamp.nanosec / 1e9)


def test_a_posture_takes_time_ignores_moves_and_leaves_progress_at_zero(driver: Driver) -> None:
    before = driver.rest()
    mark, state_mark = driver.truths.mark(), driver.states.mark()
    driver.request(go2_api.STAND_DOWN)
    started = driver.wait_truth(lambda t: t["changing"] == "StandDown", "StandDown", mark)
    during = driver.truths.mark()  # from here on, the first truth not changing is the end
    driver.walk(0.4, 0.3)  # Moves while lying down: ignored
    done = driver.wait_truth(lambda t: not t["changing"], "StandDown to finish", during)
    assert done["mono"] - started["mono"] >= POSTURE_SECONDS - 0.05
    assert done["posture"] == "lying" and done["mode"] == SportMode.LIE_DOWN
    assert (done["x"], done["y"], done["yaw"]) == (before["x"], before["y"], before["yaw"])
    assert done["moves"] - before["moves"] == done["moves_ignored"] - before["moves_ignored"] > 0
    states = driver.states.since(state_mark)
    assert all(s.progress == 0 for s in states)  # postures do not raise progress
    assert any(s.mode == SportMode.LIE_DOWN and 0.09 < s.body_height < 0.31 for s in states)
    # Up again: StandUp locks the joints (Moves still ignored), BalanceStand lets it walk.
    driver.request(go2_api.STAND_UP)
    driver.wait_truth(
        lambda t: t["mode"] == SportMode.JOINT_LOCK and not t["changing"], "StandUp to finish", mark
    )
    driver.request(go2_api.BALANCE_STAND)
    up = driver.wait_truth(
        lambda t: t["mode"] == SportMode.BALANCE_STAND and not t["changing"], "BalanceStand", mark
    )
    assert up["posture"] == "standing" and up["body_height"] == 0.32


def test_cmd_vel_reaches_the_driver_only_through_the_relay(
    driver: Driver, client: RosClient
) -> None:
    relay_in = client.node.get_subscriptions_info_by_topic("/cmd_vel")
    assert [i.node_name for i in relay_in] == ["twist_mux"]
    driver_in = client.node.get_subscriptions_info_by_topic("/cmd_vel_out")
    assert "shadowhound_sim_driver" in [i.node_name for i in driver_in]
    before = driver.rest()
    cmd_vel = client.publisher(Twist, "/cmd_vel")
    wait_until(cmd_vel.get_subscription_count, TIMEOUT, "the relay")
    mark = driver.truths.mark()
    driver.walk(0.2, 0.5, publisher=cmd_vel)
    moving = driver.wait_truth(lambda t: t["moving"], "motion through the relay", mark)
    assert moving["moves"] > before["moves"]
    driver.rest()


def test_webrtc_requests_with_a_parameter_that_is_not_json_are_dropped(driver: Driver) -> None:
    before = driver.rest()
    records = driver.records.mark()
    driver.request(go2_api.SIT, parameter="{not json")
    record = driver.record(go2_api.SIT, records)
    assert not record["accepted"] and record["note"].startswith("dropped by the driver")
    driver.request(go2_api.STOP_MOVE, topic="")  # an empty topic means the sport topic
    assert driver.record(go2_api.STOP_MOVE, records)["accepted"]
    after = driver.wait_truth(lambda t: t["stop_moves"] == before["stop_moves"] + 1, "the StopMove")
    assert after["requests_dropped"] == before["requests_dropped"] + 1
    assert after["requests"] == before["requests"] + 1  # the Sit never reached the robot
    assert after["posture"] == "standing" and after["mode"] == SportMode.BALANCE_STAND


def test_battery_state_drains_from_the_level_asked_for(driver: Driver, client: RosClient) -> None:
    battery = client.subscribe(BatteryState, "/battery_state")
    first = battery.wait_for(lambda _m: True, TIMEOUT, "a battery state")
    later = battery.wait_for(
        lambda m: m.percentage < first.percentage, TIMEOUT, "the battery to drain", battery.mark()
    )
    assert 0.0 < later.percentage < first.percentage <= 0.5
    assert abs(driver.truth()["battery"] / 100 - later.percentage) < 0.02


def test_without_a_relay_cmd_vel_reaches_nothing_and_there_is_no_battery_or_detections(
    client: RosClient,
) -> None:
    process = NodeProcess(
        "-r",
        "__ns:=/bare",
        command="sim-driver",
        options=(
            "--no-relay",
            "--camera-rate-hz",
            "0",
            "--start-posture",
            "lying",
            "--detector",
            "none",
        ),
    )
    bare = Driver(client, "/bare")
    try:
        bare.wait_ready(process)
        cmd_vel = client.publisher(Twist, "/bare/cmd_vel")
        names = dict(client.node.get_topic_names_and_types())
        assert "/bare/battery_state" not in names and "/bare/odom" in names
        assert "/bare/detections" not in names  # --detector none
        assert cmd_vel.get_subscription_count() == 0
        bare.walk(0.3, 0.5, publisher=cmd_vel)
        after = bare.wait_truth(lambda _t: True, "the truth after Twists on cmd_vel")
        assert (after["twists"], after["moves"]) == (0, 0)  # nothing came from cmd_vel
        mark = bare.truths.mark()
        bare.walk(0.3, 0.3)  # the same on cmd_vel_out reaches the robot (lying: it ignores it)
        arrived = bare.wait_truth(lambda t: t["moves"] >= 1, "Moves from cmd_vel_out", mark)
        assert arrived["moves_ignored"] == arrived["moves"] and not arrived["moving"]
        assert arrived["posture"] == "lying" and arrived["battery"] is None
        state = bare.states.latest()
        assert go2_api.posture_of(state.mode, state.body_height) is Posture.LYING
    finally:
        bare.close()
        assert process.stop(signal.SIGTERM) == 0, process.output()[-2000:]


def test_several_robots_get_robot_i_names_and_twist_mux_feeds_none_of_them(
    client: RosClient,
) -> None:
    process = NodeProcess(
        "-r",
        "__ns:=/fleet",
        command="sim-driver",
        options=("--robots", "2", "--camera-rate-hz", "0"),
    )
    robots = [Driver(client, f"/fleet/robot{i}") for i in range(2)]
    try:
        for robot in robots:
            robot.wait_ready(process)
        assert robots[0].odom.latest().child_frame_id == "robot0/base_link"
        names = dict(client.node.get_topic_names_and_types())
        assert "/fleet/odom" not in names and "/fleet/robot1/go2_states" in names
        relayed = client.publisher(Twist, "/fleet/cmd_vel")  # into twist_mux: not namespaced
        prefixed = client.publisher(Twist, "/fleet/robot0/cmd_vel")  # nobody listens
        wait_until(relayed.get_subscription_count, TIMEOUT, "the relay")
        robots[0].walk(0.3, 0.5, publisher=relayed)
        robots[0].walk(0.3, 0.5, publisher=prefixed)
        assert robots[0].truth()["moves"] == robots[1].truth()["moves"] == 0
        mark = robots[0].truths.mark()
        robots[0].walk(0.3, 0.5)
        robots[0].wait_truth(lambda t: t["moving"], "robot0 to walk", mark)
        assert robots[1].truth()["moves"] == 0 and not robots[1].truth()["moving"]
    finally:
        for robot in robots:
            robot.close()
        assert process.stop(signal.SIGTERM) == 0, process.output()[-2000:]


def test_in_process_the_truth_is_one_call_away(client: RosClient) -> None:
    from shadowhound.sim_driver.driver import SimDriver

    driver = SimDriver(
        context=client.context,
        namespace="/inproc_truth",
        options={"camera_rate_hz": 0.0, "relay": False, "odom_delay": 0.0},
    )
    for node in driver.nodes:
        client.executor.add_node(node)
    try:
        assert driver.nodes == [driver]  # no relay asked for
        published = client.subscribe(String, "/inproc_truth/sim_driver/truth")
        out = client.publisher(Twist, "/inproc_truth/cmd_vel_out")
        wait_until(out.get_subscription_count, TIMEOUT, "the in-process driver")
        msg = Twist()
        msg.angular.z = 0.5
        out.publish(msg)
        wait_until(lambda: driver.truth().moving, TIMEOUT, "the robot to turn")
        truth = driver.truth()
        assert (truth.moves, truth.posture, truth.mode) == (
            1,
            Posture.STANDING,
            SportMode.LOCOMOTION,
        )
        seen = published.wait_for(
            lambda m: json.loads(m.data)["moves"] == 1, TIMEOUT, "the published truth"
        )
        assert json.loads(seen.data).keys() == driver.truth_dict().keys()
    finally:
        for node in driver.nodes:
            client.executor.remove_node(node)
        driver.close()
        driver.destroy_node()


def test_the_driver_detects_what_its_camera_sees_in_the_odom_frame(client: RosClient) -> None:
    # The driver as a detector: the objects in view (field of view, occlusion as the
    # simulator's camera has them), at their true centres in the odometry frame.
    from shadowhound_interfaces.msg import DetectionArray

    from shadowhound.config import SimConfig
    from shadowhound.robot.sim.robot import SimRobot
    from shadowhound.robot.sim.scene import World, WorldObject
    from shadowhound.sim_driver.driver import Faults, SimDriver

    world = World(
        objects=(
            WorldObject("crate", 0.0, 2.0, radius=0.3, height=0.6),
            WorldObject("lamp", 0.0, 4.0, radius=0.2, height=0.4),  # hidden behind the crate
            WorldObject("shelf", 0.2, 5.0, radius=0.3, height=2.0),  # tall: seen over it
            WorldObject("bin", 0.0, -2.0),  # behind the robot
            WorldObject("stool", 2.0, 0.5),  # 76 degrees to the right: outside the view
        )
    )
    sim = SimRobot(SimConfig(time_scale=1.0), world=world)
    sim.reset(0.0, 0.0, math.pi / 2)  # facing +y: odometry and body frames differ
    inbox = client.subscribe(DetectionArray, "/inproc_detect/detections")
    driver = SimDriver(
        sim,
        context=client.context,
        namespace="/inproc_detect",
        options={"camera_rate_hz": 0.0, "relay": False, "navigate_to_pose": False},
    )
    for node in driver.nodes:
        client.executor.add_node(node)
    try:
        msg = inbox.wait_for(lambda _m: True, TIMEOUT, "detections from the driver")
        assert msg.header.frame_id == "odom"
        seen = {d.label: d for d in msg.detections}
        assert set(seen) == {"crate", "shelf"}, set(seen)
        for d in msg.detections:
            true = world.find(d.label)
            assert true is not None and d.header.frame_id == ""  # the array's frame
            assert (d.position.x, d.position.y) == (true.x, true.y)
            assert math.isclose(d.radius, true.radius, rel_tol=1e-6) and d.confidence == 1.0
        first = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        later = inbox.wait_for(lambda _m: True, TIMEOUT, "the next detections", inbox.mark())
        period = later.header.stamp.sec + later.header.stamp.nanosec * 1e-9 - first
        assert 0.0 < period < 5.0  # a steady stream, not one message
        assert driver.truth_dict()["detections"] >= 2
        # The camera fault blinds the detector too; cleared, the detections come back.
        driver.robots[0].faults = Faults(camera=False)
        time.sleep(0.2)  # an array already on its way arrives
        blind, count = inbox.mark(), driver.truth_dict()["detections"]
        time.sleep(1.5)  # three detector periods
        assert inbox.since(blind) == [] and driver.truth_dict()["detections"] == count
        driver.robots[0].faults = Faults()
        inbox.wait_for(lambda _m: True, TIMEOUT, "detections after the fault", inbox.mark())
    finally:
        for node in driver.nodes:
            client.executor.remove_node(node)
        driver.close()
        driver.destroy_node()


def test_the_relay_gives_the_joystick_priority_while_it_speaks() -> None:
    from shadowhound.sim_driver.twist_mux import MuxInput, forwards

    joy, nav = MuxInput("cmd_vel_joy", 10, 0.5), MuxInput("cmd_vel", 5, 0.5)
    inputs = [joy, nav]
    assert forwards(inputs, nav, now=100.0)  # the joystick never spoke
    joy.last = 100.0
    assert forwards(inputs, joy, now=100.1) and not forwards(inputs, nav, now=100.4)
    assert forwards(inputs, nav, now=100.6)  # the joystick's message has expired


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--odom-delay", "9"], "odom_delay must be in 0..5, got 9.0"),
        (["--start-posture", "kneeling"], "invalid choice: 'kneeling'"),
        (["--ros-args", "-p", "battery:=101.0"], "battery must be in 0..100, got 101.0"),
        (["--ros-args", "-p", "lidar:=true"], "unknown ROS parameter(s): lidar"),
        (["--stand-up-mode", "5"], "stand_up_mode must be one of 0, 1, 6, 7"),
    ],
)
def test_bad_options_and_parameters_exit_2_with_what_is_allowed(
    args: list[str], message: str
) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "shadowhound", "sim-driver", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr
