"""Go2RosRobot: a Unitree Go2 driven through go2_ros2_sdk's ROS 2 topics (the Robot protocol).

- motion: geometry_msgs/Twist on `cmd_vel`, capped, and re-published at 10 Hz while non-zero
  (go2_ros2_sdk and twist_mux drop a stream that goes quiet; the skills also command every tick);
- postures and tricks: go2_interfaces/WebRtcReq on `webrtc_req` with sport api ids on
  `rt/api/sport/request`; each waits for `go2_states.progress` to return to 0 (the robot queues
  sport commands) or, if the robot never reports busy, for a short settle;
- state: pose and body velocity from `odom` (nav_msgs/Odometry), posture from acknowledged
  commands; odometry older than `odom_timeout` while motion is under way makes `get_state`
  raise RobotError, so the motion step fails at once with a clear message and the agent stops
  the robot (after a stop the last state is returned with `connected` False, and motion is
  refused until odometry is back);
- camera: `camera/image_raw` (sensor_msgs/Image) or a topic ending in `compressed`.

The robot has its own rclpy node and executor thread, so it works inside the MissionNode
process (sharing its context) or in a plain script (it then initialises a private context).
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, replace

import rclpy
from geometry_msgs.msg import Twist
from go2_interfaces.msg import Go2State, WebRtcReq
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import CompressedImage, Image

from ..camera import to_camera_frame
from ..ros.convert import raw_image_frame
from ..state import CameraFrame, Posture, RobotState, Scan, normalize_angle
from . import go2_api
from .base import RobotError

_RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
_SENSOR = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                     reliability=ReliabilityPolicy.BEST_EFFORT)
_KEEPALIVE_PERIOD = 0.1  # 10 Hz, as DIMOS streams Twist to the Go2

# Sport api ids that take the robot from one posture to the next (sitting is left with RiseSit).
_STEPS: dict[tuple[Posture, Posture], tuple[int, ...]] = {
    (Posture.STANDING, Posture.STANDING): (go2_api.STAND_UP, go2_api.BALANCE_STAND),
    (Posture.LYING, Posture.STANDING): (go2_api.STAND_UP, go2_api.BALANCE_STAND),
    (Posture.SITTING, Posture.STANDING): (go2_api.RISE_SIT, go2_api.BALANCE_STAND),
    (Posture.STANDING, Posture.SITTING): (go2_api.SIT,),
    (Posture.STANDING, Posture.LYING): (go2_api.STAND_DOWN,),
}


@dataclass(frozen=True)
class Go2RosConfig:
    """Where go2_ros2_sdk's topics are and how long to wait for them.

    Topic names are relative to `namespace` (e.g. `robot0` for go2_ros2_sdk's multi-robot
    `robot{i}/` prefix) unless they start with '/'. An empty camera topic turns the camera off.
    """

    namespace: str = ""
    cmd_vel_topic: str = "cmd_vel"
    webrtc_topic: str = "webrtc_req"
    odom_topic: str = "odom"
    state_topic: str = "go2_states"
    camera_topic: str = "camera/image_raw"
    odom_timeout: float = 0.5  # seconds without odometry before get_state raises
    command_timeout: float = 10.0  # seconds a posture (or a trick beyond its length) may take
    settle: float = 0.5  # seconds to wait for a busy report before taking a command as done
    max_linear_speed: float = 1.0  # m/s, the Go2 caps DIMOS uses
    max_angular_speed: float = 2.0  # rad/s
    node_name: str = "shadowhound_go2"


class Go2RosRobot:
    """The Robot protocol over go2_ros2_sdk. Posture starts as standing (how a Go2 boots)."""

    def __init__(self, config: Go2RosConfig | None = None, *,
                 context: Context | None = None) -> None:
        self.config = c = config or Go2RosConfig()
        self.name = f"go2 ({c.namespace.strip('/')})" if c.namespace.strip("/") else "go2"
        self._own_context = context is None and not rclpy.ok()
        if self._own_context:
            context = Context()
            rclpy.init(context=context)
        elif context is None:
            context = rclpy.get_default_context()
        self._context = context
        self._lock = threading.Lock()
        self._wake = threading.Event()  # stop() and e-stop wake sleeps and waits early
        self._odom: tuple[float, RobotState] | None = None  # (monotonic receipt, state)
        self._state_seq = 0  # go2_states received so far
        self._progress: list[tuple[float, int]] = []  # recent (receipt, progress), newest last
        self._frame: CameraFrame | None = None
        self._posture = Posture.STANDING
        self._command = (0.0, 0.0, 0.0)
        self._halted = True  # no velocity commanded since the last stop()
        self._last_sent = 0.0
        self._estopped = False
        self._closed = False
        self._started = time.monotonic()
        # use_global_arguments=False: the mission node's own remappings and parameters
        # (`-r __ns:=...`) must not move the robot's topics; `namespace` does that explicitly.
        self.node = Node(c.node_name, namespace="/" + c.namespace.strip("/"), context=context,
                         use_global_arguments=False, start_parameter_services=False)
        try:
            self._build_interfaces()
        except Exception as exc:  # rclpy raises several types for bad names
            self.node.destroy_node()
            raise RobotError(f"cannot create the Go2 topics: {exc}") from exc
        self._executor = SingleThreadedExecutor(context=context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="go2-ros", daemon=True)
        self._thread.start()

    def _build_interfaces(self) -> None:
        c, n = self.config, self.node
        self._twist_pub = n.create_publisher(Twist, c.cmd_vel_topic, _RELIABLE)
        self._request_pub = n.create_publisher(WebRtcReq, c.webrtc_topic, _RELIABLE)
        n.create_subscription(Odometry, c.odom_topic, self._on_odom, _SENSOR)
        n.create_subscription(Go2State, c.state_topic, self._on_state, _RELIABLE)
        if c.camera_topic:
            compressed = c.camera_topic.rstrip("/").endswith("compressed")
            n.create_subscription(CompressedImage if compressed else Image, c.camera_topic,
                                  self._on_compressed if compressed else self._on_image, _SENSOR)
        n.create_timer(_KEEPALIVE_PERIOD, self._keep_alive)
        n.create_timer(5.0, self._warn_without_odometry)

    def _spin(self) -> None:
        try:
            while not self._closed and self._context.ok():
                self._executor.spin_once(timeout_sec=0.1)
        except ExternalShutdownException:
            pass  # the process is shutting ROS down; close() still cleans up

    def topic(self, name: str) -> str:
        """The full name of one of the robot's topics (for messages to people)."""
        return self.node.resolve_topic_name(name)

    # -- callbacks (executor thread; short) ----------------------------------------------

    def _on_odom(self, msg: Odometry) -> None:
        p, q, t = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        with self._lock:
            previous = self._odom[1] if self._odom else None
            step = math.hypot(p.x - previous.x, p.y - previous.y) if previous else 0.0
            turn = abs(normalize_angle(yaw - previous.yaw)) if previous else 0.0
            state = RobotState(
                x=p.x, y=p.y, yaw=normalize_angle(yaw), vx=t.linear.x, vy=t.linear.y,
                wz=t.angular.z, posture=self._posture, stamp=time.monotonic(),
                distance_travelled=(previous.distance_travelled if previous else 0.0) + step,
                angle_turned=(previous.angle_turned if previous else 0.0) + turn)
            self._odom = (time.monotonic(), state)

    def _on_state(self, msg: Go2State) -> None:
        with self._lock:
            self._state_seq += 1
            self._progress = [*self._progress[-49:], (time.monotonic(), int(msg.progress))]

    def _on_image(self, msg: Image) -> None:
        try:
            frame = raw_image_frame(msg.data, msg.width, msg.height, msg.encoding, msg.step,
                                    source="go2")
        except ValueError as exc:
            self.node.get_logger().warning(f"dropped a camera frame: {exc}",
                                           throttle_duration_sec=5.0)
            return
        self._frame = frame

    def _on_compressed(self, msg: CompressedImage) -> None:
        try:
            self._frame = replace(to_camera_frame(bytes(msg.data)), source="go2")
        except ValueError as exc:
            self.node.get_logger().warning(f"dropped a camera frame: {exc}",
                                           throttle_duration_sec=5.0)

    def _keep_alive(self) -> None:
        with self._lock:
            command, due = self._command, time.monotonic() - self._last_sent >= 0.08
        if any(command) and due and not self._estopped:
            self._publish_twist(command)

    def _warn_without_odometry(self) -> None:
        if self._odom is None:
            self.node.get_logger().warning(
                f"no odometry on {self.topic(self.config.odom_topic)} yet: is go2_ros2_sdk (or "
                "`shadowhound sim-driver`) running, with the same ROS_DOMAIN_ID and RMW?",
                throttle_duration_sec=30.0)

    # -- Robot protocol ------------------------------------------------------------------

    def get_state(self) -> RobotState:
        """The latest state. Raises RobotError when odometry is stale (older than
        `odom_timeout`) while motion is under way (velocity commanded since the last `stop`):
        a closed loop must not steer on an old pose. After `stop` the last state comes back
        with `connected` False, so reports and plans still work, and `send_velocity` refuses
        to start moving blind."""
        state = self.last_state()
        if not state.connected:
            with self._lock:
                halted = self._halted
            if not halted:
                raise RobotError(self._odometry_problem())
        return state

    def last_state(self) -> RobotState:
        """The last known state without raising: `connected` is False when odometry is stale."""
        with self._lock:
            odom, posture, estopped = self._odom, self._posture, self._estopped
        fresh = odom is not None and time.monotonic() - odom[0] <= self.config.odom_timeout
        base = odom[1] if odom is not None else RobotState()
        return replace(base, posture=posture, estopped=estopped, connected=fresh,
                       stamp=time.monotonic())

    def _odometry_problem(self) -> str:
        topic = self.topic(self.config.odom_topic)
        if self._odom is None:
            waited = time.monotonic() - self._started
            return (f"no odometry received on {topic} in {waited:.1f} s: is go2_ros2_sdk "
                    "running, with the same ROS_DOMAIN_ID and RMW?")
        age = time.monotonic() - self._odom[0]
        return (f"no odometry on {topic} for {age:.1f} s: is go2_ros2_sdk running and the "
                "robot connected (WebRTC allows one client: close the phone app)?")

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        values = (float(vx), float(vy), float(wz))
        if not all(math.isfinite(v) for v in values):
            raise RobotError(f"velocity must be finite numbers, got {values}")
        c = self.config
        norm = math.hypot(values[0], values[1])
        scale = c.max_linear_speed / norm if norm > c.max_linear_speed else 1.0
        command = (values[0] * scale, values[1] * scale,
                   max(-c.max_angular_speed, min(c.max_angular_speed, values[2])))
        if any(command) and not self.last_state().connected:
            raise RobotError(self._odometry_problem() + " Not moving without odometry.")
        with self._lock:
            if self._estopped:
                return  # like the simulator: motion is ignored while the e-stop is latched
            self._command = command
            self._halted = False
        self._publish_twist(command)

    def stop(self) -> None:
        with self._lock:
            self._command = (0.0, 0.0, 0.0)
            self._halted = True
        self._publish_twist((0.0, 0.0, 0.0))
        self._request(go2_api.STOP_MOVE, priority=1)
        self._wake.set()

    def emergency_stop(self) -> None:
        """Zero Twist and StopMove now; motion is ignored until `release_estop`."""
        with self._lock:
            self._estopped = True
        self.stop()

    def release_estop(self) -> None:
        with self._lock:
            self._estopped = False

    def set_posture(self, posture: Posture) -> None:
        posture = Posture(posture)
        with self._lock:
            current, estopped = self._posture, self._estopped
        if estopped:
            raise RobotError("e-stop is latched; release it before changing posture")
        with self._lock:
            self._command = (0.0, 0.0, 0.0)
        self._publish_twist((0.0, 0.0, 0.0))  # the robot must be still before it changes posture
        path = [current, posture]
        if Posture.STANDING not in path:  # sitting <-> lying goes through standing
            path = [current, Posture.STANDING, posture]
        for a, b in zip(path, path[1:], strict=False):
            for api_id in _STEPS[(a, b)]:
                self._run_request(api_id, f"{b.value} (api id {api_id})", 0.0)
            with self._lock:
                self._posture = b

    def perform(self, trick: str) -> None:
        info = go2_api.TRICKS.get(trick)
        if info is None:
            raise RobotError(f"unknown trick {trick!r}; known: {', '.join(go2_api.TRICKS)}")
        with self._lock:
            posture, estopped = self._posture, self._estopped
        if estopped or posture is not Posture.STANDING:
            why = "the e-stop is latched" if estopped else f"the robot is {posture.value}"
            raise RobotError(f"cannot perform {trick} while {why}; stand up first")
        self._run_request(info.api_id, f"{trick} (api id {info.api_id})", info.duration)

    def now(self) -> float:
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            self._wake.clear()
            self._wake.wait(seconds)

    def get_camera_frame(self) -> CameraFrame | None:
        return self._frame

    def get_scan(self) -> Scan | None:
        """None: the driver's `scan` topic is not subscribed yet (issue 15, phase 2)."""
        return None

    def close(self) -> None:
        if self._closed:
            return
        if self._context.ok():
            self.stop()
        self._closed = True
        self._thread.join(2.0)
        self._executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        if self._own_context:
            rclpy.try_shutdown(context=self._context)

    # -- sport requests ------------------------------------------------------------------

    def _publish_twist(self, command: tuple[float, float, float]) -> None:
        msg = Twist()
        msg.linear.x, msg.linear.y, msg.angular.z = command
        with self._lock:
            self._last_sent = time.monotonic()
        if self._context.ok():
            self._twist_pub.publish(msg)

    def _request(self, api_id: int, parameter: str = "", priority: int = 0) -> None:
        if self._context.ok():
            self._request_pub.publish(WebRtcReq(id=0, topic=go2_api.SPORT_TOPIC, api_id=api_id,
                                                parameter=parameter, priority=priority))

    def _run_request(self, api_id: int, what: str, expected: float) -> None:
        """Send one sport request and wait until the robot is idle again (see module doc)."""
        sent = time.monotonic()
        self._request(api_id)
        deadline = sent + expected + self.config.command_timeout
        busy = False
        while True:
            with self._lock:
                reports = [p for t, p in self._progress if t > sent]
                estopped = self._estopped
            if estopped:
                raise RobotError(f"the e-stop was pressed while waiting for {what}")
            busy = busy or any(p != 0 for p in reports)
            idle = bool(reports) and reports[-1] == 0
            if idle and (busy or time.monotonic() - sent >= self.config.settle):
                return
            if time.monotonic() > deadline:
                topic = self.topic(self.config.state_topic)
                seen = "never reported idle" if reports else "no messages"
                raise RobotError(
                    f"no completion of {what} within {deadline - sent:.0f} s: {topic} "
                    f"{seen} (progress should return to 0); check that go2_ros2_sdk is running "
                    "and connected, and that nothing else (the phone app) holds the robot")
            time.sleep(0.01)
