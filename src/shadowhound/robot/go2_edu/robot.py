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

The robot has its own rclpy node and executor thread, as the go2_ros2_sdk Go2's has.

Long because: it is the one Robot implementation over unitree_ros2, whose protocol methods and
ROS callbacks share one node, one executor thread and one lock; what needs no ROS is go2/'s,
imported (go2/api: the sport API table, go2/motion and go2/odometry: late poses, go2/posture).
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable, Mapping
from itertools import count

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from unitree_api.msg import Request
from unitree_go.msg import LowState, SportModeState

from ...robot_config import Go2EduRobotSettings
from ...state import CameraFrame, Posture, RobotState, Scan
from ...world import Belief
from ...world.image_sighting import Bearing
from ...world.objects import KnownObject
from ..base import RobotError, TrickInfo
from ..go2 import api as go2_api
from ..go2.motion import MAX_LATENCY, MotionTracker
from ..go2.odometry import OdometryIntake, OdometryLimits
from ..go2.posture import PostureWatch, SportBody, capped, finite_velocity, trick_info
from ..navigator import Navigator

__all__ = ["Go2EduRobot"]

_RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)  # type: ignore[no-untyped-call]  # rclpy
_KEEPALIVE_PERIOD = 0.1  # Moves renewed at 10 Hz
_DRIVEN_SETTLE = 2.0  # seconds the body may still move after a posture or a trick


class Go2EduRobot:
    """The Robot protocol over unitree_ros2."""

    time_scale = 1.0  # a real robot's clock is the wall clock
    realtime = True
    tricks: Mapping[str, TrickInfo] = go2_api.offered(
        ai_mode=False
    )  # unitree_ros2 does not switch motion modes

    def __init__(
        self, config: Go2EduRobotSettings | None = None, *, context: Context | None = None
    ) -> None:
        self.config = c = config or Go2EduRobotSettings()
        namespace = c.namespace.strip("/")
        self.name = f"go2_edu ({namespace})" if namespace else "go2_edu"
        self.description = "Go2 EDU over unitree_ros2" + (
            f" (namespace /{namespace})" if namespace else ""
        )
        self._own_context = context is None and not rclpy.ok()
        if self._own_context:
            context = Context()
            rclpy.init(context=context)
        elif context is None:
            context = rclpy.get_default_context()
        self._context = context
        self._lock = threading.Lock()  # state; held briefly, never while publishing
        self._send_lock = threading.Lock()  # orders Moves and StopMoves as they go out
        self._wake = threading.Event()  # stop() and e-stop wake sleeps early
        self._tracker = MotionTracker(
            linear_accel=c.linear_accel, angular_accel=c.angular_accel, latency=c.state_latency
        )
        self._intake = OdometryIntake(
            self._tracker,
            OdometryLimits(
                max_speed=c.max_linear_speed + 0.25, max_yaw_rate=c.max_angular_speed + 0.5
            ),
        )
        self._state_at: float | None = None  # monotonic receipt of the last sport state
        self._posture = Posture.STANDING  # until the sport state says otherwise
        self._posture_seen = False  # the sport state has shown a posture (then a change is news)
        self._battery: tuple[float, float] | None = None  # (receipt, percent)
        self._command = (0.0, 0.0, 0.0)
        self._halted = True  # no velocity commanded since the last stop()
        self._closed = False
        self._started = time.monotonic()
        self._ids = count(1)  # request ids (header.identity.id)
        self._postures = PostureWatch(
            self._check_estop, "", c.command_timeout, stale=max(1.0, c.state_timeout)
        )
        # a posture or a trick may move the body until self._body.driven_until
        self._body = SportBody(
            self._postures, self._request, self._halt, self._lock, _DRIVEN_SETTLE
        )
        # use_global_arguments=False: the mission node's remappings must not move these topics.
        self.node = Node(
            c.node_name,
            namespace="/" + namespace,
            context=context,
            use_global_arguments=False,
            start_parameter_services=False,
        )
        try:
            n = self.node
            self._request_pub = n.create_publisher(Request, c.request_topic, _RELIABLE)
            n.create_subscription(SportModeState, c.state_topic, self._on_state, _RELIABLE)
            n.create_subscription(LowState, c.low_state_topic, self._on_low_state, _RELIABLE)
            n.create_timer(_KEEPALIVE_PERIOD, self._keep_alive)
        except Exception as exc:  # rclpy raises several types for bad names
            self.node.destroy_node()  # type: ignore[no-untyped-call]  # rclpy
            raise RobotError(f"cannot create the Go2 EDU topics: {exc}") from exc
        self._postures.topic = self.topic(c.state_topic)
        self._executor = SingleThreadedExecutor(context=context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="go2-edu-ros", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            while not self._closed and self._context.ok():
                self._executor.spin_once(timeout_sec=0.1)
        except ExternalShutdownException:
            pass  # the process is shutting ROS down; close() still cleans up

    def topic(self, name: str) -> str:
        """The full name of one of the robot's topics (for messages to people)."""
        return self.node.resolve_topic_name(name)

    @property
    def latency(self) -> float:
        """The most the sport state may lag now: measured (or configured), else MAX_LATENCY."""
        with self._lock:
            return self._tracker.latency_bound

    # -- callbacks (executor thread; short) ----------------------------------------------

    def _on_state(self, msg: SportModeState) -> None:
        now = time.monotonic()
        stamp = msg.stamp.sec + msg.stamp.nanosec * 1e-9
        x, y, yaw = float(msg.position[0]), float(msg.position[1]), float(msg.imu_state.rpy[2])
        elsewhere = now < self._body.driven_until
        with self._lock:
            fault = self._intake.receive(now, stamp, x, y, yaw, driven_elsewhere=elsewhere)
            self._state_at = now
            moving = not self._halted
        if fault is not None and moving:
            self.stop()  # the pose is not believable: never steer on it
        posture = self._postures.observe(int(msg.mode), float(msg.body_height))
        if posture is None:
            return
        with self._lock:
            was, self._posture = self._posture if self._posture_seen else posture, posture
            self._posture_seen = True
            moving = not self._halted
        if was is Posture.STANDING and posture is not was and not self._postures.commanded:
            if moving:  # a fall, or the remote: Moves would be ignored or worse
                self.stop()
            self.node.get_logger().warning(  # type: ignore[no-untyped-call]  # rclpy
                f"{self._postures.topic} shows the robot {posture.value} "
                f"({self._postures.describe()}) without a command from ShadowHound: a fall?"
            )

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

    def get_state(self) -> RobotState:
        """The latest state. Raises RobotError when the sport state is stale while motion is
        under way, or when its pose is not believed."""
        state = self.last_state()
        with self._lock:
            halted, untrusted = self._halted, self._intake.problem(time.monotonic())
        if untrusted:
            raise RobotError(f"the sport state's pose is not trusted: {untrusted}")
        if not state.connected and not halted:
            raise RobotError(self._state_problem())
        return state

    def last_state(self) -> RobotState:
        """The last known state without raising: `connected` is False when it is stale."""
        now = time.monotonic()
        with self._lock:
            x, y, yaw = self._tracker.pose(now)
            vx, vy, wz = self._tracker.velocity(now)
            state_at, battery = self._state_at, self._battery
            travel = (self._intake.distance, self._intake.turned, self._intake.moving)
            posture, estopped = self._posture, self._body.estopped
        fresh = state_at is not None and now - state_at <= self.config.state_timeout
        level = battery[1] if battery and now - battery[0] <= self.config.battery_timeout else None
        return RobotState(
            x=x,
            y=y,
            yaw=yaw,
            vx=vx,
            vy=vy,
            wz=wz,
            posture=posture,
            battery=level,
            distance_travelled=travel[0],
            angle_turned=travel[1],
            time_moving=travel[2],
            stamp=now,
            estopped=estopped,
            connected=fresh,
        )

    def _state_problem(self) -> str:
        topic = self.topic(self.config.state_topic)
        if self._state_at is None:
            return (
                f"no sport state received on {topic} in {time.monotonic() - self._started:.1f} "
                "s: is the Go2 EDU (or `shadowhound sim-driver --interface unitree_ros2`) on "
                "this network, with the same ROS_DOMAIN_ID?"
            )
        return f"no sport state on {topic} for {time.monotonic() - self._state_at:.1f} s"

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Body-frame velocity as Moves (renewed at 10 Hz); all zero is a stop (StopMove)."""
        values = finite_velocity(vx, vy, wz)
        if not any(values):
            with self._lock:
                halted = self._halted
            if not halted:
                self.stop()
            return
        c = self.config
        command = capped(values, c.max_linear_speed, c.max_angular_speed)
        if not self.last_state().connected:
            raise RobotError(self._state_problem() + " Not moving without a pose.")
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
        with self._send_lock:
            with self._lock:
                if self._body.estopped:
                    return  # motion is ignored while the e-stop is latched
                self._command, self._halted = command, False
                walks = self._posture is Posture.STANDING  # else the robot ignores it
                self._intake.command(time.monotonic(), *(command if walks else (0.0, 0.0, 0.0)))
            self._move(command)

    def stop(self) -> None:
        """StopMove now (thread-safe); the keep-alive goes quiet. Under the send lock, so no
        Move read before the stop can go out after it."""
        now = time.monotonic()
        with self._send_lock:
            with self._lock:
                self._command, self._halted = (0.0, 0.0, 0.0), True
            self._request(go2_api.STOP_MOVE)
        with self._lock:
            self._intake.command(now, 0.0, 0.0, 0.0)
        self._wake.set()

    def emergency_stop(self) -> None:
        """StopMove now; motion and postures are refused until `release_estop`."""
        self._body.latch(True)
        self.stop()

    def release_estop(self) -> None:
        self._body.latch(False)

    def watch_estop(self, listener: Callable[[bool], None]) -> None:
        """No e-stop source of its own (the mission node and the dashboard have theirs)."""

    def set_posture(self, posture: Posture) -> None:
        """Go to `posture` through standing, one sport request at a time (go2/posture.py's
        steps), each done when the sport state shows the posture it leads to."""
        self._body.set_posture(posture)

    def _halt(self) -> None:
        with self._lock:
            moving = not self._halted
        if moving:
            self.stop()

    def perform(self, trick: str) -> None:
        info = trick_info(trick)
        if info.api_id in go2_api.AI_MODE_TRICKS:
            raise RobotError(f"{trick} (api id {info.api_id}) needs the 'ai' motion mode")
        self._body.perform(trick)

    def say(self, text: str) -> None:
        raise RobotError("this Go2 EDU has no voice here (unitree_ros2 carries no speech)")

    def now(self) -> float:
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            self._wake.clear()
            self._wake.wait(seconds)

    def get_camera_frame(self) -> CameraFrame | None:
        return None

    def get_scan(self) -> Scan | None:
        return None

    def belief(self) -> Belief | None:
        return None

    def known_objects(self) -> tuple[KnownObject, ...]:
        return ()

    def bearings(self) -> tuple[Bearing, ...]:
        return ()

    def in_view(self) -> None:
        return None  # no camera here: nothing can be watched for by sight

    def look(self) -> None:
        return None

    def vocabulary(self) -> frozenset[str]:
        return frozenset()

    def navigator(self) -> Navigator | None:
        return None

    def close(self) -> None:
        if self._closed:
            return
        if self._context.ok():
            self.stop()
        self._closed = True
        self._thread.join(2.0)
        self._executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()  # type: ignore[no-untyped-call]  # rclpy
        if self._own_context:
            rclpy.try_shutdown(context=self._context)

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

    def _check_estop(self, doing: str) -> None:
        self._body.check_estop(doing)
