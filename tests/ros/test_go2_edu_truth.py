"""The go2_edu backend (a Go2 EDU through Unitree's unitree_ros2) judged by the simulated
driver's ground truth, over real DDS (issue 25, part 6).

`shadowhound sim-driver --interface unitree_ros2` (unitree_api/Request on /api/sport/request
in; unitree_go/SportModeState on lf/sportmodestate, late as odometry is, and LowState on
lf/lowstate out) and `shadowhound node -p robot:=go2_edu` run as separate processes, as in
test_go2_truth.py; this process reads the driver's ground truth (`sim_driver/truth`), never the
state the agent steers on. Every wait is on DDS matches (both sides) or on messages, never a
fixed sleep.

Skipped without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import json
import math
import signal
from collections.abc import Iterator
from typing import Any

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "unitree_api", "unitree_go")

from std_msgs.msg import String  # noqa: E402
from unitree_api.msg import Request  # noqa: E402

from tests.ros.rosclient import (  # noqa: E402
    Agent,
    NodeProcess,
    RosClient,
    wait_matched,
    wait_until,
)
from tests.ros.test_go2_truth import (  # noqa: E402
    DEGREES,
    METRES,
    MISSION,
    TIMEOUT,
    frame_of,
    free_port,
)

PING_API_ID = 0  # no sport command: the driver answers it as not simulated and records it
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


class EduTruth:
    """The simulated driver's own topics (under `ns`), and its unitree_ros2 request topic."""

    def __init__(self, client: RosClient, ns: str = "") -> None:
        self.client = client
        self.requests = client.subscribe(String, f"{ns}/sim_driver/requests")
        self.sport = client.publisher(Request, f"{ns}/api/sport/request")  # the last writer
        self.truth = client.subscribe(String, f"{ns}/sim_driver/truth")  # last reader: 50 Hz

    def wait_ready(self, driver: NodeProcess) -> None:
        wait_matched(
            self.client,
            "the simulated Go2 EDU",
            [self.requests, self.truth],
            [self.sport],
            ping=self.ping,
            alive=driver.check_alive,
        )

    def request(self, api_id: int, parameter: str = "") -> None:
        msg = Request(parameter=parameter)
        msg.header.identity.api_id = api_id
        self.sport.publish(msg)

    def ping(self) -> Any:
        """A request the driver drops (its parameter is not JSON) and records."""
        mark = self.requests.mark()
        self.request(PING_API_ID, "{ping")
        return lambda: any(
            json.loads(m.data)["api_id"] == PING_API_ID for m in self.requests.since(mark)
        )

    def close(self) -> None:
        self.client.destroy(self.requests, self.sport, self.truth)

    def now(self) -> dict[str, Any]:
        mark = self.truth.mark()
        return json.loads(
            self.truth.wait_for(lambda _m: True, 5.0, "the driver's truth", mark).data
        )

    def wait(self, match: Any, what: str, timeout: float = TIMEOUT) -> dict[str, Any]:
        mark = self.truth.mark()
        return json.loads(
            self.truth.wait_for(lambda m: match(json.loads(m.data)), timeout, what, mark).data
        )

    def still(self) -> dict[str, Any]:
        """Truth once the robot has not moved for a while (every record of 0.5 s still)."""
        first = self.wait(lambda t: not t["moving"] and not t["changing"], "the robot still")
        later = self.wait(lambda t: t["mono"] - first["mono"] >= 0.5, "half a second of truth")
        assert not later["moving"], later
        return later


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_edu_truth_client")
    yield c
    c.close()


@pytest.mark.parametrize(
    "options",
    [(), ("--state-rate-hz", "10", "--odom-delay", "0.5")],
    ids=["sport state 10 Hz 0.2 s late", "sport state 10 Hz 0.5 s late"],
)
def test_the_mission_ends_on_target_in_truth(client: RosClient, options: tuple[str, ...]) -> None:
    # No namespace: the robot's own topics are at the root (/api/sport/request, /lf/...).
    driver = NodeProcess(
        command="sim-driver",
        options=("--interface", "unitree_ros2", "--start-posture", "lying", *options),
    )
    node = NodeProcess(
        "-p",
        "robot:=go2_edu",
        "-p",
        "enable_web_ui:=true",
        "-p",
        f"web_interface_port:={free_port()}",
    )
    agent, truth = Agent(client), EduTruth(client)
    try:
        agent.wait_ready(node)
        truth.wait_ready(driver)
        wait_until(
            lambda: agent.robot_state()["connected"], TIMEOUT, "the node's Go2 EDU sport state"
        )
        start = truth.still()
        assert start["posture"] == "lying", start
        wait_until(
            lambda: agent.robot_state().get("posture") == "lying",
            TIMEOUT,
            "the node to report the robot lying",
        )
        status = agent.robot.mark()
        final = agent.run(MISSION, 90.0)
        end = truth.still()
        ahead, left, turned = frame_of(start, end)
        assert final.startswith("COMPLETED: "), (final, node.output()[-3000:])
        assert end["posture"] == "standing", end
        assert math.hypot(ahead - 1.0, left) < METRES, (ahead, left)
        assert abs(turned - 90.0) < DEGREES, turned
        assert end["moves_ignored"] == start["moves_ignored"], (start, end)
        reported = json.loads(
            agent.robot.wait_for(
                lambda _m: True, 5.0, "robot status", max(status, agent.robot.mark())
            ).data
        )
        assert math.hypot(reported["x"] - end["x"], reported["y"] - end["y"]) < METRES
        assert abs(math.degrees(math.remainder(reported["yaw"] - end["yaw"], math.tau))) < DEGREES
        # The battery comes from LowState's bms_state.soc (whole percent).
        assert reported["battery"] == pytest.approx(end["battery"] or 100.0, abs=1.0), reported
    finally:
        agent.close()
        truth.close()
        codes = {"node": node.stop(signal.SIGINT), "driver": driver.stop(signal.SIGTERM)}
        assert codes == {"node": 0, "driver": 0}, (node.output()[-3000:], driver.output()[-3000:])
