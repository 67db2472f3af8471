"""RosRobot: a Unitree Go2 over ROS 2, whichever driver carries it: what go2/robot.py
(go2_ros2_sdk's topics) and go2_edu/robot.py (Unitree's unitree_ros2) share.

- ROS: the robot has its own rclpy node and executor thread, so it works inside the MissionNode
  process (sharing its context) or in a plain script (it then initialises a private context,
  and shuts it down on `close`). The node ignores the process's global ROS arguments: the
  mission node's remappings (`-r __ns:=...`) must not move the robot's topics; `namespace`
  does that explicitly.
- threads: the protocol methods and the ROS callbacks share one lock (state; held briefly,
  never while publishing) and a send lock (orders velocity and StopMoves as they go out).
- the body: the sport API's, driven alike on both (go2/'s modules without rclpy): velocity
  tracked against late poses (go2/motion, go2/odometry), postures and tricks one request at a
  time (go2/posture's SportBody), every stop a StopMove, sleeps woken early by a stop.

A backend builds its topics (`_build_interfaces`), sends sport requests (`_request`), says why
it is blind (`_pose_problem`), and from its callbacks feeds the pose (`_intake`, `_pose_at`),
the posture (`_observe_posture`) and the battery (`_battery`). It starts in three steps:
`RosRobot.__init__`, its own parts, then `_open_node` and `_start_spinning`.
"""

from __future__ import annotations

import threading
import time
from abc import abstractmethod
from collections.abc import Callable
from typing import ClassVar, Generic, Protocol, TypeVar

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from ..state import Pose2D, Posture, RobotState
from .base import BaseRobot, RobotError, Stall
from .go2 import api as go2_api
from .go2.motion import MotionTracker
from .go2.odometry import OdometryIntake, OdometryLimits
from .go2.posture import PostureWatch, SportBody

__all__ = ["DRIVEN_SETTLE", "KEEPALIVE_PERIOD", "RELIABLE", "RosRobot", "SportSettings"]

RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
KEEPALIVE_PERIOD = 0.1  # Moves renewed at 10 Hz (the robot drops one after about a second)
DRIVEN_SETTLE = 2.0  # seconds the body may still move after a posture, a trick (or Nav2)


class SportSettings(Protocol):
    """What the settings of every Go2 backend over ROS hold (robot_config)."""

    namespace: str
    node_name: str
    state_topic: str
    battery_timeout: float
    command_timeout: float
    max_linear_speed: float
    max_angular_speed: float
    linear_accel: float
    angular_accel: float


SettingsT = TypeVar("SettingsT", bound=SportSettings)


class RosRobot(BaseRobot, Generic[SettingsT]):
    """The Robot protocol's common part for a Go2 over ROS 2: a real robot, on the wall clock
    (BaseRobot's)."""

    # What the pose comes from, in messages to people ("odometry is not trusted: ...").
    pose_source: ClassVar[str]

    def __init__(
        self,
        config: SettingsT,
        context: Context | None,
        *,
        name: str,
        description: str,
        pose_latency: float | None,
        pose_timeout: float,
    ) -> None:
        """`name` and `description` say what the robot is (the namespace is added to both);
        `pose_latency`: seconds the pose lags the robot (None: measured); `pose_timeout`:
        seconds without a pose after which the robot is blind."""
        self.config = c = config
        namespace = c.namespace.strip("/")
        self.name = f"{name} ({namespace})" if namespace else name
        self.description = description + (f" (namespace /{namespace})" if namespace else "")
        self._own_context = context is None and not rclpy.ok()
        if self._own_context:
            context = Context()
            rclpy.init(context=context)
        elif context is None:
            context = rclpy.get_default_context()
        self._context = context
        self._lock = threading.Lock()  # state; held briefly, never while publishing
        self._send_lock = threading.Lock()  # orders velocity and StopMoves as they go out
        self._wake = threading.Event()  # stop() and e-stop wake sleeps and waits early
        self._tracker = MotionTracker(
            linear_accel=c.linear_accel, angular_accel=c.angular_accel, latency=pose_latency
        )
        # The pose is checked before it is believed (go2/odometry); the odometer is its own.
        self._intake = OdometryIntake(
            self._tracker,
            OdometryLimits(
                max_speed=c.max_linear_speed + 0.25, max_yaw_rate=c.max_angular_speed + 0.5
            ),
        )
        self._pose_timeout = pose_timeout
        self._pose_at: float | None = None  # monotonic receipt of the last pose
        self._posture = Posture.STANDING  # until the robot's state says otherwise
        self._posture_seen = False  # the state has shown a posture (a change then means news)
        self._battery: tuple[float, float] | None = None  # (receipt, percent)
        self._command = (0.0, 0.0, 0.0)
        self._halted = True  # no velocity commanded since the last stop()
        self._closed = False
        self._started = time.monotonic()
        self._postures = PostureWatch(
            self._check_estop, "", c.command_timeout, stale=max(1.0, pose_timeout)
        )
        # A posture or a trick (or Nav2) may move the body until self._body.driven_until.
        self._body = SportBody(self._postures, self._request, self._halt, self._lock, DRIVEN_SETTLE)

    def _open_node(self, what: str) -> None:
        """The robot's node with its topics (`_build_interfaces`), and its executor; `what`
        names the robot in the error when a topic cannot be made."""
        c = self.config
        # use_global_arguments=False: the mission node's own remappings and parameters
        # (`-r __ns:=...`) must not move the robot's topics; `namespace` does that explicitly.
        self.node = Node(
            c.node_name,
            namespace="/" + c.namespace.strip("/"),
            context=self._context,
            use_global_arguments=False,
            start_parameter_services=False,
        )
        try:
            self._build_interfaces()
        except Exception as exc:  # rclpy raises several types for bad names
            self.node.destroy_node()
            raise RobotError(f"cannot create the {what} topics: {exc}") from exc
        self._postures.topic = self.topic(c.state_topic)
        self._executor = SingleThreadedExecutor(context=self._context)
        self._executor.add_node(self.node)

    def _start_spinning(self, thread_name: str) -> None:
        """The executor thread: callbacks run from here on."""
        self._thread = threading.Thread(target=self._spin, name=thread_name, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            while not self._closed and self._context.ok():
                self._executor.spin_once(timeout_sec=0.1)
        except ExternalShutdownException:
            pass  # the process is shutting ROS down; close() still cleans up

    # -- what a backend writes -------------------------------------------------------------

    @abstractmethod
    def _build_interfaces(self) -> None:
        """Create the node's publishers, subscriptions and timers."""

    @abstractmethod
    def _request(self, api_id: int, parameter: dict[str, object] | None = None) -> None:
        """Send one sport request (nothing once ROS is shut down)."""

    @abstractmethod
    def _pose_problem(self) -> str:
        """Why the robot is blind: no pose yet, or none for a while (for RobotError)."""

    def _locate(self, now: float) -> tuple[Pose2D, int, tuple[float, float, float]]:
        """The pose now in the robot's world frame, with the relocalizations seen and their
        composition (RobotState.relocalized, jumps). With self._lock held. Here the pose's own
        frame is the world, and it never relocalizes."""
        return Pose2D(*self._tracker.pose(now)), 0, (0.0, 0.0, 0.0)

    # -- shared by the backends ------------------------------------------------------------

    def topic(self, name: str) -> str:
        """The full name of one of the robot's topics (for messages to people)."""
        return self.node.resolve_topic_name(name)

    @property
    def latency(self) -> float:
        """The most the pose may lag now: measured (or configured), else MAX_LATENCY."""
        with self._lock:
            return self._tracker.latency_bound

    def stalls(self, since: float) -> tuple[Stall, ...]:
        """The pose stream's stalls seen since `since` (go2/odometry)."""
        with self._lock:
            return self._intake.stalls(since)

    def _observe_posture(self, mode: int, body_height: float) -> None:
        """A state message's mode and body height (executor thread): a posture change nobody
        here asked for (a fall, the remote) stops the robot and is logged."""
        posture = self._postures.observe(mode, body_height)
        if posture is None:
            return
        with self._lock:
            was, self._posture = self._posture if self._posture_seen else posture, posture
            self._posture_seen = True
            moving = not self._halted
        if was is Posture.STANDING and posture is not was and not self._postures.commanded:
            # Moves would be ignored or worse: stop now (the running step then fails on the
            # posture, SkillContext.check).
            if moving:
                self.stop()
            self.node.get_logger().warning(
                f"{self._postures.topic} shows the robot {posture.value} "
                f"({self._postures.describe()}) without a command from ShadowHound: a fall?"
                + (" The robot was stopped." if moving else "")
            )

    def get_state(self) -> RobotState:
        """The latest state. Raises RobotError when the pose is stale (older than its timeout)
        while motion is under way (velocity commanded since the last `stop`): a closed loop
        must not steer on an old pose; or when the pose is not trusted. After `stop` the last
        state comes back with `connected` False, so reports and plans still work, and
        `send_velocity` refuses to start moving blind."""
        state = self.last_state()
        with self._lock:
            halted, untrusted = self._halted, self._intake.problem(time.monotonic())
        if untrusted:
            raise RobotError(f"{self.pose_source} is not trusted: {untrusted}")
        if not state.connected and not halted:
            raise RobotError(self._pose_problem())
        return state

    def last_state(self) -> RobotState:
        """The last known state without raising: `connected` is False when the pose is stale."""
        now = time.monotonic()
        with self._lock:
            pose, relocalized, jumps = self._locate(now)
            own = self._tracker.pose(now)  # odometry's, before the world's corrections
            vx, vy, wz = self._tracker.velocity(now)
            pose_at, battery = self._pose_at, self._battery
            travel = (self._intake.distance, self._intake.turned, self._intake.moving)
            posture, estopped = self._posture, self._body.estopped
        fresh = pose_at is not None and now - pose_at <= self._pose_timeout
        level = battery[1] if battery and now - battery[0] <= self.config.battery_timeout else None
        return RobotState(
            x=pose.x,
            y=pose.y,
            yaw=pose.yaw,
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
            relocalized=relocalized,
            jumps=jumps,
            odometry=(own[0], own[1], own[2]),
        )

    def _command_velocity(
        self,
        command: tuple[float, float, float],
        send: Callable[[tuple[float, float, float]], None],
    ) -> None:
        """Keep `command` (the keep-alive renews it) and `send` it, unless the e-stop is
        latched. The robot ignores velocity unless standing: the tracker predicts no motion
        then."""
        with self._send_lock:
            with self._lock:
                if self._body.estopped:
                    return  # like the simulator: motion is ignored while the e-stop is latched
                self._command, self._halted = command, False
                walks = self._posture is Posture.STANDING
                self._intake.command(time.monotonic(), *(command if walks else (0.0, 0.0, 0.0)))
            send(command)

    def stop(self) -> None:
        """StopMove now (thread-safe); the keep-alive goes quiet."""
        self._stop_move(time.monotonic())

    def _stop_move(self, now: float) -> None:
        """StopMove, under the send lock, so no velocity read before the stop can go out after
        it (the robot would walk on for a second); the tracker stops at `now`."""
        with self._send_lock:
            with self._lock:
                self._command, self._halted = (0.0, 0.0, 0.0), True
            self._request(go2_api.STOP_MOVE)
        with self._lock:
            self._intake.command(now, 0.0, 0.0, 0.0)
        self._wake.set()

    def _halt(self) -> None:
        """Stop if moving (velocity commanded since the last stop)."""
        with self._lock:
            moving = not self._halted
        if moving:
            self.stop()

    def emergency_stop(self) -> None:
        """StopMove now; motion and postures are refused until `release_estop`."""
        self._body.latch(True)
        self.stop()

    def release_estop(self) -> None:
        self._body.latch(False)

    def _check_estop(self, doing: str) -> None:
        self._body.check_estop(doing)

    def sleep(self, seconds: float) -> None:
        """Wall-clock seconds; a stop or an e-stop ends the sleep early."""
        if seconds > 0:
            self._wake.clear()
            self._wake.wait(seconds)

    def close(self) -> None:
        """Stop, end the threads, destroy the node, and the context when it is the robot's
        own. Safe to call twice."""
        if self._closed:
            return
        if self._context.ok():
            self.stop()
        self._closed = True
        self._closing()
        self._thread.join(2.0)
        self._executor.shutdown(timeout_sec=1.0)
        self._destroy_node()
        if self._own_context:
            rclpy.try_shutdown(context=self._context)

    def _closing(self) -> None:  # noqa: B027 (a default: nothing more runs)
        """End what the backend runs besides the executor (called once, `_closed` set)."""

    def _destroy_node(self) -> None:
        """Destroy the node (and what the backend made on it), after the executor's end."""
        self.node.destroy_node()
