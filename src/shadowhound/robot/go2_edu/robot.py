"""Go2EduRobot: a Unitree Go2 EDU driven through Unitree's own ROS 2 interface (unitree_ros2,
CycloneDDS on the robot; the Robot protocol).

- commands: unitree_api/Request on `/api/sport/request`, the sport API id in
  `header.identity.api_id` and its parameter as JSON (go2_api's table, the same ids as
  go2_ros2_sdk's): Move (1008, {"x","y","z"}) re-sent at 10 Hz while non-zero (the robot drops
  a Move after about a second), StopMove (1003) on every stop; postures as on the Go2
  (go2/posture.py's steps: StandUp then BalanceStand, Sit, RiseSit, StandDown), each done
  when the state shows the posture it leads to.
- state: unitree_go/SportModeState on `lf/sportmodestate`: position (x, y) and the IMU's yaw
  (`imu_state.rpy[2]`) are the pose in the robot's odometry frame, late over the link, so
  go2/motion.py's MotionTracker predicts the pose now and go2/odometry.py's intake checks it;
  `mode` and `body_height` give the posture through go2_api's one table (PostureWatch).
  Sport state older than `state_timeout` while motion is under way makes `get_state` raise.
- battery: unitree_go/LowState on `lf/lowstate`, `bms_state.soc` (percent).
- no camera, scan, map, detector, Nav2 or voice here: unitree_ros2 carries them otherwise.

What every Go2 over ROS has (its own node and executor thread, the locks, stops, the e-stop
latch, the state) is ros_base.py's RosRobot, as the go2_ros2_sdk Go2's is; what needs no ROS is
go2/'s, imported (go2/api: the sport API table, go2/motion and go2/odometry: late poses,
go2/posture).
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from itertools import count

from rclpy.context import Context
from unitree_api.msg import Request
from unitree_go.msg import LowState, SportModeState

from ...robot_config import Go2EduRobotSettings
from ...state import Posture
from ..base import RobotError, TrickInfo
from ..go2 import api as go2_api
from ..go2.motion import MAX_LATENCY
from ..go2.posture import capped, finite_velocity, trick_info
from ..ros_base import KEEPALIVE_PERIOD, RELIABLE, RosRobot

__all__ = ["Go2EduRobot"]


class Go2EduRobot(RosRobot[Go2EduRobotSettings]):
    """The Robot protocol over unitree_ros2."""

    pose_source = "the sport state's pose"
    # unitree_ros2 does not switch motion modes: the tricks of the normal one
    tricks: Mapping[str, TrickInfo] = go2_api.offered(ai_mode=False)

    def __init__(
        self, config: Go2EduRobotSettings | None = None, *, context: Context | None = None
    ) -> None:
        c = config or Go2EduRobotSettings()
        super().__init__(
            c,
            context,
            name="go2_edu",
            description="Go2 EDU over unitree_ros2",
            pose_latency=c.state_latency,
            pose_timeout=c.state_timeout,
        )
        self._ids = count(1)  # request ids (header.identity.id)
        self._open_node("Go2 EDU")
        self._start_spinning("go2-edu-ros")

    def _build_interfaces(self) -> None:
        c, n = self.config, self.node
        self._request_pub = n.create_publisher(Request, c.request_topic, RELIABLE)
        n.create_subscription(SportModeState, c.state_topic, self._on_state, RELIABLE)
        n.create_subscription(LowState, c.low_state_topic, self._on_low_state, RELIABLE)
        n.create_timer(KEEPALIVE_PERIOD, self._keep_alive)

    # -- callbacks (executor thread; short) ----------------------------------------------

    def _on_state(self, msg: SportModeState) -> None:
        now = time.monotonic()
        stamp = msg.stamp.sec + msg.stamp.nanosec * 1e-9
        x, y, yaw = float(msg.position[0]), float(msg.position[1]), float(msg.imu_state.rpy[2])
        elsewhere = now < self._body.driven_until
        with self._lock:
            fault = self._intake.receive(now, stamp, x, y, yaw, driven_elsewhere=elsewhere)
            self._pose_at = now
            moving = not self._halted
        if fault is not None and moving:
            self.stop()  # the pose is not believable: never steer on it
        self._observe_posture(int(msg.mode), float(msg.body_height))

    def _on_low_state(self, msg: LowState) -> None:
        with self._lock:
            self._battery = (time.monotonic(), float(msg.bms_state.soc))

    def _keep_alive(self) -> None:
        with self._send_lock:
            with self._lock:
                command, estopped = self._command, self._body.estopped
            if any(command) and not estopped:
                self._move(command)

    # -- Robot protocol ------------------------------------------------------------------

    def _pose_problem(self) -> str:
        topic = self.topic(self.config.state_topic)
        if self._pose_at is None:
            return (
                f"no sport state received on {topic} in {time.monotonic() - self._started:.1f} "
                "s: is the Go2 EDU (or `shadowhound sim-driver --interface unitree_ros2`) on "
                "this network, with the same ROS_DOMAIN_ID?"
            )
        return f"no sport state on {topic} for {time.monotonic() - self._pose_at:.1f} s"

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Body-frame velocity as Moves (renewed at 10 Hz); all zero is a stop (StopMove)."""
        values = finite_velocity(vx, vy, wz)
        if not any(values):
            self._halt()
            return
        c = self.config
        command = capped(values, c.max_linear_speed, c.max_angular_speed)
        if not self.last_state().connected:
            raise RobotError(self._pose_problem() + " Not moving without a pose.")
        with self._lock:
            starting, estopped = self._halted, self._body.estopped
            untrusted = self._intake.problem(time.monotonic())
            lag = self._tracker.latency
        if untrusted:
            raise RobotError(f"the sport state's pose is not trusted: {untrusted}. Not moving.")
        if starting and lag >= MAX_LATENCY - 0.05:
            raise RobotError(f"the sport state lags the robot by {lag:.1f} s or more; not moving")
        standing = self._postures.current() is Posture.STANDING
        if starting and standing and not estopped and not self._postures.balanced():
            self.set_posture(Posture.STANDING)  # joints held after a StandUp: balance first
        self._command_velocity(command, self._move)

    def set_posture(self, posture: Posture) -> None:
        """Go to `posture` through standing, one sport request at a time (go2/posture.py's
        steps), each done when the sport state shows the posture it leads to."""
        self._body.set_posture(posture)

    def perform(self, trick: str) -> None:
        info = trick_info(trick)
        if info.api_id in go2_api.AI_MODE_TRICKS:
            raise RobotError(f"{trick} (api id {info.api_id}) needs the 'ai' motion mode")
        self._body.perform(trick)

    def say(self, text: str) -> None:
        raise RobotError("this Go2 EDU has no voice here (unitree_ros2 carries no speech)")

    # -- requests out --------------------------------------------------------------------

    def _move(self, command: tuple[float, float, float]) -> None:
        """One Move; the caller holds the send lock."""
        x, y, z = command
        self._request(go2_api.MOVE, {"x": x, "y": y, "z": z})

    def _request(self, api_id: int, parameter: dict[str, object] | None = None) -> None:
        if not self._context.ok():
            return
        msg = Request()
        msg.header.identity.id = next(self._ids)
        msg.header.identity.api_id = api_id
        msg.parameter = json.dumps(parameter) if parameter else ""
        self._request_pub.publish(msg)
