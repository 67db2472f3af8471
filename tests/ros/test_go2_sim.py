"""The Go2 robot end to end: `shadowhound node -p robot:=go2` drives `shadowhound sim-driver`.

Two processes (the mission node and the simulated go2_ros2_sdk driver, in go2_ros2_sdk's
multi-robot namespace robot0) talk over real DDS on loopback; this process watches the
driver's own topics (odom, go2_states, sim_driver/requests, sim_driver/truth: the judge) and
injects faults. Skipped
without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
"""

from __future__ import annotations

import json
import math
import signal
from collections.abc import Iterator
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces")

from geometry_msgs.msg import Twist  # noqa: E402
from go2_interfaces.msg import Go2State, WebRtcReq  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from std_msgs.msg import Empty, String  # noqa: E402

from tests.ros.rosclient import (  # noqa: E402
    Agent,
    NodeProcess,
    RosClient,
    wait_matched,
    wait_until,
)

NS = "/robot0"
TIMEOUT = 30.0
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


class Driver:
    """The simulated driver's topics, seen from the test client."""

    def __init__(self, client: RosClient) -> None:
        self.client = client
        self.odom = client.subscribe(Odometry, f"{NS}/odom")
        self.states = client.subscribe(Go2State, f"{NS}/go2_states")
        self.requests = client.subscribe(String, f"{NS}/sim_driver/requests")
        self.fault = client.publisher(String, f"{NS}/sim_driver/fault")
        self.cmd_vel = client.publisher(Twist, f"{NS}/cmd_vel")
        self.webrtc = client.publisher(WebRtcReq, f"{NS}/webrtc_req")  # the last writer
        self.truth = client.subscribe(String, f"{NS}/sim_driver/truth")  # last reader: 50 Hz

    def wait_ready(self, process: NodeProcess) -> None:
        """Until the driver and this client have matched every topic both ways."""

        def ping() -> Any:  # a request the driver drops (not JSON) and records
            mark = self.requests.mark()
            self.webrtc.publish(WebRtcReq(id=0, topic="", api_id=0, parameter="{", priority=0))
            return lambda: 0 in self.api_ids(mark)

        wait_matched(
            self.client,
            "the simulated driver",
            [self.odom, self.states, self.requests, self.truth],
            [self.fault, self.cmd_vel, self.webrtc],
            ping=ping,
            alive=process.check_alive,
        )

    def pose(self) -> tuple[float, float, float]:
        """The true pose (the driver's odometry is late: the truth is the judge)."""
        t = json.loads(self.truth.latest().data)
        return t["x"], t["y"], t["yaw"]

    def api_ids(self, mark: int = 0) -> list[int]:
        return [json.loads(m.data)["api_id"] for m in self.requests.since(mark)]

    def wait_moving(self) -> None:
        mark = self.truth.mark()
        self.truth.wait_for(
            lambda m: abs(json.loads(m.data)["vx"]) > 0.1, TIMEOUT, "the robot to walk", mark
        )

    def wait_still(self, what: str) -> None:
        """Until the truth says the body is still. Not go2_states: it is `odom_delay` late like
        odometry, so right after a stop it can still show the robot from before it moved."""
        mark = self.truth.mark()

        def still(m: String) -> bool:
            t = json.loads(m.data)
            return max(abs(t["vx"]), abs(t["vy"]), abs(t["wz"])) < 1e-3 and not t["moving"]

        self.truth.wait_for(still, 10.0, what, mark)

    def set_faults(self, faults: dict[str, Any]) -> None:
        """Publish faults and wait until the driver's truth shows them in force (a mission sent
        right after must not race the fault message)."""
        self.fault.publish(String(data=json.dumps(faults)))
        want = {k: v for k, v in faults.items() if k != "delay_ms"}
        mark = self.truth.mark()
        self.truth.wait_for(
            lambda m: (
                all(json.loads(m.data)["faults"].get(k, True) == v for k, v in want.items())
                and (faults or not json.loads(m.data)["faults"]["drop_commands"])
            ),
            10.0,
            f"the faults {faults} in force",
            mark,
        )


@pytest.fixture(scope="module")
def rig() -> Iterator[tuple[Agent, Driver]]:
    client = RosClient("shadowhound_go2_test_client")
    driver_process = NodeProcess(
        "-r", f"__ns:={NS}", "-p", "camera_rate_hz:=2.0", command="sim-driver"
    )
    node = NodeProcess(
        "-p",
        "robot:=go2",
        "-p",
        f"robot_namespace:={NS[1:]}",
        "-p",
        "camera_topic:=/robot0/camera/image_raw",
    )
    agent, driver = Agent(client), Driver(client)
    try:
        agent.wait_ready(node)
        driver.wait_ready(driver_process)
        wait_until(
            lambda: agent.robot_state()["connected"],
            TIMEOUT,
            "the node's Go2 robot to receive odometry",
        )
        yield agent, driver
        node.check_alive()
        driver_process.check_alive()
    finally:
        codes = {"node": node.stop(signal.SIGINT), "driver": driver_process.stop(signal.SIGTERM)}
        client.close()
    assert codes == {"node": 0, "driver": 0}, (
        node.output()[-2000:],
        driver_process.output()[-2000:],
    )


def test_walk_forward_then_turn_left_ends_at_1_0_90_in_the_drivers_odometry(rig) -> None:
    agent, driver = rig
    x0, y0, yaw0 = driver.pose()
    final = agent.run("walk forward 1 meter then turn left 90 degrees", 60.0)
    assert final.startswith("COMPLETED: "), final
    wait_until(
        lambda: not json.loads(driver.truth.latest().data)["moving"], 10.0, "the robot to be still"
    )
    x, y, yaw = driver.pose()
    # In the frame where the mission started: 1 m ahead, heading +90 degrees.
    dx, dy = x - x0, y - y0
    c, s = math.cos(yaw0), math.sin(yaw0)
    ahead, left = dx * c + dy * s, -dx * s + dy * c
    turned = math.degrees(math.remainder(yaw - yaw0, 2 * math.pi))
    assert abs(ahead - 1.0) < 0.05 and abs(left) < 0.05, (ahead, left)
    assert abs(turned - 90.0) < 3.0, turned


def test_postures_and_a_trick_arrive_with_their_sport_api_ids(rig) -> None:
    agent, driver = rig
    mark = driver.requests.mark()
    final = agent.run("sit down then stand up then lie down then stand up then say hello", 60.0)
    assert final.startswith("COMPLETED: "), final
    ids = [i for i in driver.api_ids(mark) if i != 1003]  # StopMove comes with every stop
    # Sit; RiseSit (ends balanced); StandDown; StandUp + BalanceStand; Hello.
    assert ids == [1009, 1010, 1005, 1004, 1002, 1016], ids
    records = [json.loads(m.data) for m in driver.requests.since(mark)]
    assert all(r["accepted"] for r in records), records
    assert driver.states.latest().mode != 10  # standing again, not sitting


def test_sitting_ignores_motion_in_the_driver(rig) -> None:
    agent, driver = rig
    assert agent.run("sit down").startswith("COMPLETED: ")
    driver.states.wait_for(lambda m: m.mode == 10 and m.progress == 0, 5.0, "sitting")
    x0, y0, _ = driver.pose()
    forward = Twist()
    forward.linear.x = 0.4
    mark = driver.odom.mark()
    for _ in range(10):  # about a second of 10 Hz cmd_vel (paced by 50 Hz odometry)
        driver.cmd_vel.publish(forward)
        sent = driver.odom.mark()
        wait_until(lambda s=sent: len(driver.odom.since(s)) >= 5, 5.0, "odometry")
    assert len(driver.odom.since(mark)) >= 50
    x, y, _ = driver.pose()
    assert math.hypot(x - x0, y - y0) < 1e-6
    assert not json.loads(driver.truth.latest().data)["moving"]
    assert agent.run("stand up").startswith("COMPLETED: ")


def test_estop_during_a_move_brings_the_drivers_velocity_to_zero(rig) -> None:
    agent, driver = rig
    mark, requests = agent.status.mark(), driver.requests.mark()
    agent.missions.publish(String(data="walk backward 3 meters"))
    driver.wait_moving()
    agent.estop.publish(Empty())
    try:
        driver.wait_still("the driver's velocity to reach zero after the e-stop")
        done = agent.status.wait_for(
            lambda m: m.data.startswith(("FAILED", "COMPLETED")),
            TIMEOUT,
            "the mission to end",
            mark,
        )
        assert done.data.startswith("FAILED: ") and "e-stop pressed" in done.data, done.data
        assert 1003 in driver.api_ids(requests)  # StopMove went to the robot too
        x0, y0, _ = driver.pose()
        assert not agent.run("walk forward 1 meter").startswith("COMPLETED")  # refused
        assert math.hypot(driver.pose()[0] - x0, driver.pose()[1] - y0) < 1e-3
    finally:
        agent.release.publish(Empty())
    agent.diagnostic(agent.diagnostics.mark(), 5.0, lambda v: v["estop"] == "false")


def test_lost_odometry_fails_the_step_clearly_and_leaves_the_robot_stopped(rig) -> None:
    agent, driver = rig
    mark = agent.status.mark()
    agent.missions.publish(String(data="walk forward 2 meters"))
    driver.wait_moving()
    driver.set_faults({"odom": False})
    try:
        done = agent.status.wait_for(
            lambda m: m.data.startswith(("FAILED", "COMPLETED")),
            TIMEOUT,
            "the mission to end",
            mark,
        )
        assert done.data.startswith("FAILED: "), done.data
        assert f"no odometry on {NS}/odom for" in done.data, done.data
        assert "The robot is stopped." in done.data, done.data
        driver.wait_still("the driver's velocity to reach zero after odometry was lost")
        status = agent.robot_state()
        assert status["connected"] is False  # the node keeps reporting, from the last state
    finally:
        driver.set_faults({})
    odom_mark = driver.odom.mark()
    driver.odom.wait_for(lambda _m: True, 5.0, "odometry to come back", odom_mark)
    assert agent.robot_state()["connected"] is True


def test_dropped_commands_fail_the_move_as_a_stall(rig) -> None:
    agent, driver = rig
    driver.set_faults({"drop_commands": True, "delay_ms": 100})
    try:
        x0, y0, _ = driver.pose()
        final = agent.run("walk forward 1 meter", 60.0)
        # A stall (no progress for 3 s), or on a loaded machine the step's own time-out:
        # either way the step fails, the robot is stopped and has not moved.
        # Or the leg's own bound: its commands used up while odometry shows no motion.
        assert final.startswith("FAILED: ") and (
            "no progress for" in final
            or "timed out after" in final
            or "the commands do not reach the robot or it ignores them" in final
        ), final
        assert "The robot is stopped." in final, final
        assert math.hypot(driver.pose()[0] - x0, driver.pose()[1] - y0) < 1e-3
    finally:
        driver.set_faults({})
    mark = driver.requests.mark()
    final = agent.run("turn right 10 degrees")
    # A rare CI failure here ("no progress for 3.0 s with 3 degrees to go") was not reproduced
    # in 20 runs: say what the driver saw when it happens again.
    records = [json.loads(m.data) for m in driver.requests.since(mark)]
    assert final.startswith("COMPLETED: "), (final, driver.truth.latest().data, records[-12:])
    assert all(json.loads(m.data)["accepted"] for m in driver.requests.since(mark))
