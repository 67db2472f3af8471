"""The contract every robot backend keeps (issue 25, part 2), run against each of them:

- "sim": SimRobot, its clock at time scale 0 (tests run it as fast as it goes); its truth is
  its own state (the simulator's state is computed, never received).
- "go2": Go2RosRobot in this process over DDS against a `shadowhound sim-driver` process (one
  per module), judged by the driver's ground truth on `sim_driver/truth`, never by the
  odometry the robot steers on. Skipped without rclpy or the interface packages unless
  SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
- "go2_edu": Go2EduRobot likewise, against `shadowhound sim-driver --interface unitree_ros2`
  (the Go2 EDU through unitree_ros2: Requests in, SportModeState and LowState out), judged by
  the same truth.

Both DDS backends run in this test process's ROS domain (tests/ros/conftest.py claims one no
other test process holds), each driver under a namespace of its own, one at a time.

The contract, as robot/base.py's docstrings state it:

- `stop` is idempotent and thread-safe: many threads stopping at once raise nothing, and the
  robot comes to rest (and stays there when stopped again).
- `emergency_stop` latches (`get_state().estopped`): velocity is then ignored without an error
  (the body does not move), `set_posture` and `perform` raise RobotError; `release_estop`
  releases, the robot stays at rest until it is commanded again, and then it walks.
- Velocity is ignored without an error while the robot is not standing (sitting, lying), and
  not kept for later: standing up does not start a walk. Who ignores it is no part of the
  contract, and differs: SimRobot drops it itself (its command log says "ignored: robot is
  sitting"); Go2RosRobot and Go2EduRobot send it on (and keep it alive at 10 Hz until a stop
  or a posture command) and the Go2 ignores it (the driver counts it in `moves_ignored`).
  While the e-stop is latched all drop it before it reaches the body.
- `get_state` raises RobotError when the robot is blind while motion is under way, and
  `send_velocity` refuses to start moving blind; `stop` still stops it. (The simulator cannot
  be blind: skipped, see SimBackend.blind.)
- `set_posture` returns once the posture is reached: the robot's state and the truth show it.
- At rest after a short walk the robot's pose agrees with the truth within 2 cm and 1 degree.
"""

from __future__ import annotations

import contextlib
import json
import math
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import pytest

from shadowhound.robot.base import Robot, RobotError
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.state import Posture, RobotState

METRES, DEGREES = 0.02, 1.0  # how far the pose at rest may be from the truth
STILL = 0.005  # metres an ignored command may move the body (none: noise only)
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@dataclass(frozen=True)
class Seen:
    """The body as it really is (the truth)."""

    x: float
    y: float
    yaw: float
    posture: Posture
    moving: bool
    changing: bool  # a posture change under way


def apart(a: Seen, b: Seen | RobotState) -> tuple[float, float]:
    """Metres and degrees between two poses."""
    return (
        math.hypot(a.x - b.x, a.y - b.y),
        abs(math.degrees(math.remainder(a.yaw - b.yaw, math.tau))),
    )


def pass_time(robot: Robot, seconds: float) -> None:
    """Let `seconds` pass on the robot's clock (the control loop's way)."""
    end = robot.now() + seconds
    while (left := end - robot.now()) > 1e-6:  # a simulator integrates no less than 1e-12 s
        robot.sleep(min(0.05, left))


class Backend(ABC):
    """One robot backend and a way to see its truth."""

    robot: Robot

    @abstractmethod
    def truth(self) -> Seen:
        """The body now."""

    @abstractmethod
    def wait_for(self, match: Callable[[Seen], bool], what: str, timeout: float = 60.0) -> Seen:
        """The truth once `match` holds (time passes meanwhile); fails after `timeout`, which
        only bounds a hung test (a loaded machine is slow)."""

    @abstractmethod
    def at_rest(self) -> Seen:
        """The truth once the body has come to rest (no motion, no posture change)."""

    @abstractmethod
    def blind(self) -> contextlib.AbstractContextManager[None]:
        """Take the robot's odometry away while inside; skips for a robot that cannot be
        blind. Call it before moving."""

    @abstractmethod
    def reset(self) -> None:
        """Standing, released, at rest: where each test starts."""

    def close(self) -> None:
        self.robot.close()

    def robot_at_rest(self, timeout: float = 60.0) -> RobotState:
        """The robot's own state once it, too, reports the body at rest."""
        end = self.robot.now() + timeout
        while True:
            state = self.robot.get_state()
            if not state.is_moving:
                return state
            if self.robot.now() > end:
                raise AssertionError(f"the robot still reports motion after {timeout} s: {state}")
            self.robot.sleep(0.02)


class SimBackend(Backend):
    def __init__(self) -> None:
        self.robot = self.sim = SimRobot(time_scale=0.0)

    def truth(self) -> Seen:
        s = self.sim.get_state()
        _t, x, y = self.sim.true_path[-1]
        return Seen(x, y, s.yaw, s.posture, s.is_moving, changing=False)

    def wait_for(self, match: Callable[[Seen], bool], what: str, timeout: float = 60.0) -> Seen:
        end = self.sim.now() + timeout
        while True:
            seen = self.truth()
            if match(seen):
                return seen
            if self.sim.now() > end:
                raise AssertionError(f"timed out after {timeout:g} s waiting for {what}: {seen}")
            self.sim.sleep(0.02)

    def at_rest(self) -> Seen:
        return self.wait_for(lambda s: not s.moving, "the body at rest")

    def blind(self) -> contextlib.AbstractContextManager[None]:
        pytest.skip(
            "SimRobot cannot be blind: its state is its own ground truth, computed on its "
            "clock, never received (get_state has nothing to lose and never raises), and it "
            "has no way to take its odometry away"
        )

    def reset(self) -> None:
        self.robot = self.sim = SimRobot(time_scale=0.0)


class DriverBackend(Backend):
    """`shadowhound sim-driver` under /NS (no map, Nav2, detector, camera or scan: what is
    judged here needs none) and a robot in this process that drives it over DDS; judged by
    the driver's truth. Subclasses say which interface the driver plays and which robot
    drives it."""

    NS: str
    NEEDS: tuple[str, ...]  # modules without which the backend skips (or fails in CI)
    REQUESTS: str  # the robot's sport request topic, relative to NS
    OPTIONS: tuple[str, ...] = (
        "--posture-seconds",
        "0.5",
        "--camera-rate-hz",
        "0",
        "--scan-rate-hz",
        "0",
        "--detector",
        "none",
        "--no-map",
        "--no-navigate-to-pose",
    )
    go2: Any  # the robot (Go2RosRobot or Go2EduRobot)

    def __init__(self) -> None:
        from tests.ros.needs import require

        require("rclpy", "shadowhound_interfaces", *self.NEEDS)
        from tests.ros.rosclient import NodeProcess, RosClient

        self.client = RosClient(f"shadowhound_{self.NS}_client")
        self.driver = NodeProcess(
            "-r", f"__ns:=/{self.NS}", command="sim-driver", options=self.OPTIONS
        )
        self.topics = self._topics()
        self.go2 = None
        try:
            self.topics.wait_ready(self.driver)
            self.robot = self.go2 = self._robot()
            self._wait_until(lambda: self.go2.last_state().connected, "odometry at the robot")
            self._prove_commands_arrive()
        except BaseException:
            self.close()
            raise

    @abstractmethod
    def _topics(self) -> Any:
        """The driver's own topics as the test client reads and writes them: `requests`,
        `fault` and `truth`, `wait_ready(driver)`, `now()`, `wait(match, what, timeout)`."""

    @abstractmethod
    def _robot(self) -> Robot:
        """The robot under test, on the test client's context."""

    def _velocity_ready(self) -> None:
        """Until velocity can reach the driver (once sport requests do)."""

    def _wait_until(self, predicate: Callable[[], Any], what: str, timeout: float = 60.0) -> Any:
        from tests.ros.rosclient import wait_until

        return wait_until(lambda: self.driver.check_alive() or predicate(), timeout, what)

    def _prove_commands_arrive(self) -> None:
        """Until the driver has matched the robot's writers: each counts the driver's reader
        (this side), then one command over it reaches the driver's records (the other side;
        a reliable writer that counts a reader loses nothing to it, see wait_matched); then
        one turn in place proves that velocity moves the body."""
        from shadowhound.robot.go2 import api as go2_api

        topic = f"/{self.NS}/{self.REQUESTS}"
        requests = next(p for p in self.go2.node.publishers if p.topic_name == topic)
        self._wait_until(lambda: requests.get_subscription_count() > 0, f"the driver's {topic}")
        mark = self.topics.requests.mark()
        self.go2.stop()  # StopMove: moves nothing
        self._wait_until(
            lambda: any(
                json.loads(m.data)["api_id"] == go2_api.STOP_MOVE
                for m in self.topics.requests.since(mark)
            ),
            "the first StopMove's record",
        )
        self._velocity_ready()
        moves = self._record()["moves"]
        self.go2.send_velocity(0.0, 0.0, 0.2)
        try:
            self._wait_until(lambda: self._record()["moves"] > moves, "the first Move's record")
        finally:
            self.go2.stop()
        self.at_rest()

    def _record(self) -> dict[str, Any]:
        """The next truth record."""
        return dict(self.topics.now())

    @staticmethod
    def _seen(record: dict[str, Any]) -> Seen:
        return Seen(
            record["x"],
            record["y"],
            record["yaw"],
            Posture(record["posture"]),
            record["moving"],
            bool(record["changing"]),
        )

    def truth(self) -> Seen:
        return self._seen(self._record())

    def wait_for(self, match: Callable[[Seen], bool], what: str, timeout: float = 60.0) -> Seen:
        return self._seen(self.topics.wait(lambda r: match(self._seen(r)), what, timeout))

    def at_rest(self, records: int = 10) -> Seen:
        """Once `records` truth records in a row (50 Hz) show the body still."""
        inbox = self.topics.truth
        mark = inbox.mark()

        def still() -> bool:
            recent = [self._seen(json.loads(m.data)) for m in inbox.since(mark)][-records:]
            return len(recent) == records and not any(s.moving or s.changing for s in recent)

        self._wait_until(still, "the body at rest")
        return self._seen(json.loads(inbox.items[-1].data))

    @contextlib.contextmanager
    def blind(self) -> Iterator[None]:
        """The driver stops publishing odometry (its `odom` fault) while inside."""
        self.topics.fault.publish(_fault({"odom": False}))
        try:
            self.topics.wait(lambda r: r["faults"]["odom"] is False, "odometry off at the driver")
            yield
        finally:
            self.topics.fault.publish(_fault({}))
            self.topics.wait(lambda r: r["faults"]["odom"] is True, "odometry on at the driver")
            self._wait_until(lambda: self.go2.last_state().connected, "odometry back")

    def reset(self) -> None:
        self.go2.release_estop()
        self.go2.stop()
        self.go2.set_posture(Posture.STANDING)
        self.at_rest()
        self.robot_at_rest()

    def close(self) -> None:
        import signal

        if self.go2 is not None:
            self.go2.close()
        self.topics.close()
        self.client.close()
        code = self.driver.stop(signal.SIGTERM)
        assert code == 0, self.driver.output()[-3000:]


class Go2Backend(DriverBackend):
    """The driver as go2_ros2_sdk's (webrtc_req, cmd_vel through its relay, odom, go2_states)
    under /contract, and a Go2RosRobot."""

    NS = "contract"
    NEEDS = ("go2_interfaces",)
    REQUESTS = "webrtc_req"

    def _topics(self) -> Any:
        from tests.ros.test_go2_truth import Truth

        return Truth(self.client, f"/{self.NS}")

    def _robot(self) -> Robot:
        from shadowhound.robot.go2.robot import Go2RosConfig, Go2RosRobot

        return Go2RosRobot(
            Go2RosConfig(namespace=self.NS, node_name="shadowhound_contract_go2"),
            context=self.client.context,
        )

    def _velocity_ready(self) -> None:
        """Velocity goes to cmd_vel through the relay: until the robot has seen the relay and
        counts its reader."""
        ns = f"/{self.NS}"
        self._wait_until(lambda: self.go2.velocity_topic == f"{ns}/cmd_vel", "the relay")
        twists = next(p for p in self.go2.node.publishers if p.topic_name == f"{ns}/cmd_vel")
        self._wait_until(lambda: twists.get_subscription_count() > 0, "the relay's cmd_vel")


class Go2EduBackend(DriverBackend):
    """The driver as a Go2 EDU behind unitree_ros2 (`--interface unitree_ros2`: Requests on
    api/sport/request in, SportModeState and LowState out) under /contract_edu, and a
    Go2EduRobot. Moves go over the request topic too: nothing more to wait for."""

    NS = "contract_edu"
    NEEDS = ("go2_interfaces", "unitree_api", "unitree_go")  # EduTruth's module needs all
    REQUESTS = "api/sport/request"
    OPTIONS = (*DriverBackend.OPTIONS, "--interface", "unitree_ros2")

    def _topics(self) -> Any:
        from tests.ros.rosclient import wait_matched
        from tests.ros.test_go2_edu_truth import EduTruth

        class Topics(EduTruth):  # made here: EduTruth's module needs ROS to import
            """EduTruth, and the driver's fault topic (`blind`), made before its sport
            writer: the ping over that one proves both."""

            def __init__(self, client: Any, ns: str) -> None:
                from std_msgs.msg import String

                self.fault = client.publisher(String, f"{ns}/sim_driver/fault")
                super().__init__(client, ns)

            def wait_ready(self, driver: Any) -> None:
                wait_matched(
                    self.client,
                    "the simulated Go2 EDU",
                    [self.requests, self.truth],
                    [self.fault, self.sport],
                    ping=self.ping,
                    alive=driver.check_alive,
                )

            def close(self) -> None:
                super().close()
                self.client.destroy(self.fault)

        return Topics(self.client, f"/{self.NS}")

    def _robot(self) -> Robot:
        from shadowhound.robot.go2_edu.robot import Go2EduRobot
        from shadowhound.robot_config import Go2EduRobotSettings

        return Go2EduRobot(
            Go2EduRobotSettings(
                namespace=self.NS,
                request_topic=self.REQUESTS,  # the robot's own is at the root: here under NS
                node_name="shadowhound_contract_go2_edu",
            ),
            context=self.client.context,
        )


def _fault(faults: dict[str, Any]) -> Any:
    from std_msgs.msg import String

    return String(data=json.dumps(faults))


BACKENDS: dict[str, Callable[[], Backend]] = {
    "sim": SimBackend,
    "go2": Go2Backend,
    "go2_edu": Go2EduBackend,
}


@pytest.fixture(scope="module", params=list(BACKENDS))
def backend(request: pytest.FixtureRequest) -> Iterator[Backend]:
    made = BACKENDS[request.param]()
    yield made
    made.close()


@pytest.fixture
def rig(backend: Backend) -> Backend:
    backend.reset()
    return backend


def walk(rig: Backend, vx: float, wz: float) -> Seen:
    """Command a walk; returns the truth once the body moves."""
    rig.robot.send_velocity(vx, 0.0, wz)
    return rig.wait_for(lambda s: s.moving, "the body to walk")


def test_stop_is_idempotent_and_thread_safe(rig: Backend) -> None:
    robot = rig.robot
    threads, stops = 16, 5
    walk(rig, -0.3, 0.3)
    start = threading.Barrier(threads + 1)
    done = threading.Event()
    errors: list[BaseException] = []

    def stopper() -> None:
        try:
            start.wait(60.0)
            for _ in range(stops):
                robot.stop()
        except BaseException as exc:  # reported below: the test fails on any
            errors.append(exc)

    def control_loop() -> None:  # the robot's clock runs on meanwhile, as in a mission
        try:
            start.wait(60.0)
            while not done.is_set():
                robot.sleep(0.01)
        except BaseException as exc:
            errors.append(exc)

    workers = [threading.Thread(target=stopper) for _ in range(threads)]
    ticker = threading.Thread(target=control_loop)
    for t in [*workers, ticker]:
        t.start()
    for t in workers:
        t.join(60.0)
    done.set()
    ticker.join(60.0)
    assert not any(t.is_alive() for t in [*workers, ticker]), "a stop hung"
    assert errors == [], errors
    rest = rig.at_rest()
    state = rig.robot_at_rest()
    assert not state.estopped and state.posture is Posture.STANDING
    robot.stop()  # at rest: stopping again changes nothing
    robot.stop()
    pass_time(robot, 0.5)
    again = rig.truth()
    assert not again.moving
    assert apart(rest, again)[0] < STILL


def test_the_estop_latches_refuses_velocity_and_postures_until_released(rig: Backend) -> None:
    robot = rig.robot
    walk(rig, 0.3, 0.0)
    robot.emergency_stop()
    robot.emergency_stop()  # pressed twice: still one latch
    stopped = rig.at_rest()
    assert robot.get_state().estopped
    robot.send_velocity(0.3, 0.0, 0.5)  # ignored: no error, no motion
    pass_time(robot, 1.0)
    latched = rig.truth()
    assert not latched.moving and apart(stopped, latched)[0] < STILL, (stopped, latched)
    with pytest.raises(RobotError, match="e-stop"):
        robot.set_posture(Posture.SITTING)
    with pytest.raises(RobotError, match="e-stop"):
        robot.perform("hello")
    assert rig.truth().posture is Posture.STANDING
    assert robot.get_state().estopped  # still latched after all that
    robot.release_estop()
    assert not robot.get_state().estopped
    pass_time(robot, 0.5)  # released, not commanded: the body stays where it is
    released = rig.truth()
    assert not released.moving and apart(stopped, released)[0] < STILL
    walk(rig, 0.3, 0.0)  # commanded again: it walks
    robot.stop()
    rig.at_rest()


@pytest.mark.parametrize("posture", [Posture.SITTING, Posture.LYING])
def test_velocity_is_ignored_while_not_standing_and_not_kept_for_later(
    rig: Backend, posture: Posture
) -> None:
    robot = rig.robot
    robot.set_posture(posture)
    before = rig.at_rest()
    robot.send_velocity(0.3, 0.0, 0.5)  # ignored: no error, no motion
    pass_time(robot, 0.6)
    after = rig.truth()
    assert not after.moving and apart(before, after)[0] < STILL, (before, after)
    assert apart(before, after)[1] < 0.5
    assert robot.get_state().posture is posture
    robot.set_posture(Posture.STANDING)  # standing up does not start the ignored walk
    pass_time(robot, 0.6)
    standing = rig.truth()
    assert not standing.moving and apart(before, standing)[0] < STILL, (before, standing)
    walk(rig, 0.3, 0.0)  # commanded while standing: it walks
    robot.stop()
    rig.at_rest()


def test_get_state_raises_when_blind_while_moving(rig: Backend) -> None:
    robot = rig.robot
    blind = rig.blind()  # skips here for a robot that cannot be blind
    walk(rig, 0.0, 0.3)  # turning in place: no room needed while blind
    try:
        with blind:

            def raised() -> RobotError | None:
                try:
                    robot.get_state()
                except RobotError as exc:
                    return exc
                return None

            end = robot.now() + 60.0  # bounds a hung test; staleness comes far sooner
            while (error := raised()) is None and robot.now() < end:
                robot.sleep(0.02)
            assert error is not None, "get_state kept answering while blind and moving"
            with pytest.raises(RobotError):
                robot.send_velocity(0.3, 0.0, 0.0)  # refuses to start moving blind
            robot.stop()  # stopping needs no odometry
            rest = rig.at_rest()
            # At rest, blind: the last state, marked stale, without an error.
            state = robot.get_state()
            assert not state.connected
            assert robot.last_state().connected is False
            assert not rest.moving
    finally:
        robot.stop()
    assert robot.get_state().connected


def test_postures_report_completion(rig: Backend) -> None:
    robot = rig.robot
    # Standing -> lying, lying -> sitting (through standing), sitting -> standing.
    for posture in (Posture.LYING, Posture.SITTING, Posture.STANDING):
        robot.set_posture(posture)  # returns once the posture is reached
        assert robot.get_state().posture is posture
        seen = rig.truth()
        assert seen.posture is posture and not seen.changing, (posture, seen)
    walk(rig, 0.2, 0.0)  # standing means walking: balanced, not merely upright
    robot.stop()
    rig.at_rest()


def test_the_pose_agrees_with_the_truth_at_rest_after_a_short_walk(rig: Backend) -> None:
    robot = rig.robot
    start = rig.at_rest()
    walk(rig, 0.3, 0.4)
    pass_time(robot, 1.5)
    robot.stop()
    end = rig.at_rest()
    state = rig.robot_at_rest()
    walked, turned = apart(start, end)
    assert walked > 0.2 and turned > 20.0, (start, end)  # it did walk and turn
    metres, degrees = apart(end, state)
    assert metres < METRES and degrees < DEGREES, (end, state)
