"""`shadowhound sim-driver`: go2_ros2_sdk's topics and behaviour, backed by a SimRobot in real time.

For running missions without a robot (`shadowhound node --ros-args -p robot:=go2` in another
terminal) and for the end-to-end tests. Names are relative, so `-r __ns:=/robot0` gives
go2_ros2_sdk's multi-robot `robot0/` prefix.

- subscribes `cmd_vel` (geometry_msgs/Twist) and `webrtc_req` (go2_interfaces/WebRtcReq: sport
  api ids on rt/api/sport/request, see go2_api); postures and tricks run one at a time, in
  order, and `go2_states.progress` is 1 while one runs or waits, like the real robot's queue;
- publishes `odom` (nav_msgs/Odometry, frames odom -> base_link), `go2_states`
  (go2_interfaces/Go2State) and `camera/image_raw` (sensor_msgs/Image rgb8, best effort);
- like the real robot, velocity is ignored while sitting or lying, and, like go2_ros2_sdk's
  twist handling, the velocity returns to zero when `cmd_vel` goes quiet for `cmd_vel_timeout`;
- `sim_driver/fault` (std_msgs/String JSON) injects faults: {"odom": false} (stop publishing
  odometry), {"states": false}, {"camera": false}, {"delay_ms": 200} (every command arrives
  late), {"drop_commands": true} (commands are lost); {} clears them all;
- `sim_driver/requests` (std_msgs/String JSON) reports every sport request it received:
  api_id, name, accepted, note, and `mono` (the driver's CLOCK_MONOTONIC, for latency figures).

Callbacks only hand commands to a command thread (which applies the injected delay) and
postures and tricks to a request thread (they take seconds); one executor serves the rest.
"""

from __future__ import annotations

import heapq
import itertools
import json
import math
import queue
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from geometry_msgs.msg import Twist
from go2_interfaces.msg import Go2State, WebRtcReq
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Image
from std_msgs.msg import String

from ..config import SimConfig
from ..robot import go2_api, scene
from ..robot.base import RobotError
from ..robot.sim import SimRobot
from ..state import Posture
from .params import DRIVER_PARAMETERS, DriverSettings, ParameterError, parse_driver
from .process import run_node

NODE_NAME = "shadowhound_sim_driver"
EXIT_OK, EXIT_USAGE = 0, 2
_RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
_SENSOR = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                     reliability=ReliabilityPolicy.BEST_EFFORT)
# Unitree SportModeState.mode values the driver reports.
_MODE_BALANCE_STAND, _MODE_POSE, _MODE_LOCOMOTION, _MODE_LIE_DOWN, _MODE_SIT = 1, 2, 3, 5, 10
_BODY_HEIGHT = {Posture.STANDING: 0.32, Posture.SITTING: 0.20, Posture.LYING: 0.08}
_NAMES = {go2_api.DAMP: "Damp", go2_api.BALANCE_STAND: "BalanceStand",
          go2_api.STOP_MOVE: "StopMove", go2_api.STAND_UP: "StandUp",
          go2_api.STAND_DOWN: "StandDown", go2_api.MOVE: "Move", go2_api.SIT: "Sit",
          go2_api.RISE_SIT: "RiseSit", **{t.api_id: t.name for t in go2_api.TRICKS.values()}}
# Sport api id -> (posture it needs, posture it leads to). Others are tricks or not simulated.
_POSTURES = {
    go2_api.STAND_UP: (None, Posture.STANDING),
    go2_api.BALANCE_STAND: (Posture.STANDING, Posture.STANDING),
    go2_api.RISE_SIT: (Posture.SITTING, Posture.STANDING),
    go2_api.SIT: (Posture.STANDING, Posture.SITTING),
    go2_api.STAND_DOWN: (None, Posture.LYING),
}
_TRICK_IDS = {t.api_id for t in go2_api.TRICKS.values()}

@dataclass
class Faults:
    """Injected faults (all off by default)."""

    odom: bool = True
    states: bool = True
    camera: bool = True
    delay: float = 0.0  # seconds every command is held back
    drop_commands: bool = False

    @classmethod
    def from_json(cls, text: str) -> Faults:
        """Parse a fault message; raises ValueError naming what is wrong."""
        data = json.loads(text) if text.strip() else {}
        if not isinstance(data, dict):
            raise ValueError("a fault message must be a JSON object")
        unknown = set(data) - {"odom", "states", "camera", "delay_ms", "drop_commands"}
        if unknown:
            raise ValueError(f"unknown fault(s) {sorted(unknown)}; known: odom, states, camera, "
                             "delay_ms, drop_commands")
        flags = {k: data[k] for k in ("odom", "states", "camera", "drop_commands") if k in data}
        if not all(isinstance(v, bool) for v in flags.values()):
            raise ValueError("odom, states, camera and drop_commands take true or false")
        delay = data.get("delay_ms", 0)
        if isinstance(delay, bool) or not isinstance(delay, (int, float)) \
                or not 0 <= delay <= 10_000:
            raise ValueError("delay_ms must be a number of milliseconds in 0..10000")
        return cls(**flags, delay=delay / 1000.0)


class SimDriver(Node):
    """A simulated go2_ros2_sdk driver node. Give `sim` to drive an existing SimRobot."""

    def __init__(self, sim: SimRobot | None = None, *, node_name: str = NODE_NAME,
                 **node_kwargs: Any) -> None:
        super().__init__(node_name, **node_kwargs)
        self.settings = self._read_parameters()
        self.sim = sim or SimRobot(SimConfig(time_scale=1.0), name="sim-driver")
        self.faults = Faults()
        self._busy = 0  # sport requests waiting or running
        self._busy_lock = threading.Lock()
        self._last_twist = 0.0  # monotonic time of the last velocity command applied
        self._moving_command = False
        self._commands: list[tuple[float, int, Callable[[], None]]] = []  # (due, seq, apply)
        self._order = itertools.count()
        self._commands_ready = threading.Condition()
        self._requests: queue.Queue[int | None] = queue.Queue()
        self._closing = False
        s = self.settings
        self._odom_pub = self.create_publisher(Odometry, "odom", _RELIABLE)
        self._state_pub = self.create_publisher(Go2State, "go2_states", _RELIABLE)
        self._camera_pub = self.create_publisher(Image, "camera/image_raw", _SENSOR)
        self._record_pub = self.create_publisher(String, "sim_driver/requests",
                                                 QoSProfile(depth=50))
        self.create_subscription(Twist, "cmd_vel", self._on_twist, _RELIABLE)
        self.create_subscription(WebRtcReq, "webrtc_req", self._on_request, _RELIABLE)
        self.create_subscription(String, "sim_driver/fault", self._on_fault, _RELIABLE)
        self.create_timer(1.0 / s.odom_rate_hz, self._publish_odom)
        self.create_timer(1.0 / s.state_rate_hz, self._publish_state)
        self.create_timer(0.05, self._watchdog)
        if s.camera_rate_hz > 0:
            self.create_timer(1.0 / s.camera_rate_hz, self._publish_camera)
        self._threads = [threading.Thread(target=self._apply_commands, name="sim-commands",
                                          daemon=True),
                         threading.Thread(target=self._run_requests, name="sim-requests",
                                          daemon=True)]
        for thread in self._threads:
            thread.start()
        self.get_logger().info(
            f"simulated Go2 ready: {self.resolve_topic_name('cmd_vel')}, "
            f"{self.resolve_topic_name('webrtc_req')} in; odom {s.odom_rate_hz:g} Hz, "
            f"go2_states {s.state_rate_hz:g} Hz, camera {s.camera_rate_hz:g} Hz out; faults on "
            f"{self.resolve_topic_name('sim_driver/fault')}")

    def _read_parameters(self) -> DriverSettings:
        unknown = sorted(set(getattr(self, "_parameter_overrides", {}))
                         - set(DRIVER_PARAMETERS) - {"use_sim_time"})
        if unknown:
            raise ParameterError(f"unknown ROS parameter(s): {', '.join(unknown)}; known: "
                                 f"{', '.join(DRIVER_PARAMETERS)}")
        values = {name: self.declare_parameter(
            name, default, ParameterDescriptor(description=text, dynamic_typing=True)).value
            for name, (default, text) in DRIVER_PARAMETERS.items()}
        return parse_driver(values)

    def close(self) -> None:
        """Stop the robot and the worker threads."""
        self._closing = True
        self.sim.stop()
        with self._commands_ready:
            self._commands_ready.notify()
        self._requests.put(None)
        for thread in self._threads:
            thread.join(2.0)

    # -- commands in (callbacks hand over; the command thread applies after any delay) ------

    def _on_twist(self, msg: Twist) -> None:
        if not self.faults.drop_commands:
            self._schedule(lambda: self._apply_velocity(msg.linear.x, msg.linear.y,
                                                        msg.angular.z))

    def _on_request(self, msg: WebRtcReq) -> None:
        api_id, parameter = int(msg.api_id), str(msg.parameter)
        if self.faults.drop_commands:
            self._record(api_id, False, "dropped (fault injection)")
        elif msg.topic != go2_api.SPORT_TOPIC:
            self._record(api_id, False, f"topic {msg.topic!r} is not {go2_api.SPORT_TOPIC}")
        else:
            self._schedule(lambda: self._apply_request(api_id, parameter))

    def _on_fault(self, msg: String) -> None:
        try:
            self.faults = Faults.from_json(msg.data)
        except ValueError as exc:  # json.JSONDecodeError is a ValueError
            self.get_logger().warning(f"ignored a fault message {msg.data!r}: {exc}")
            return
        self.get_logger().warning(f"fault injection now: {self.faults}")

    def _schedule(self, apply: Callable[[], None]) -> None:
        with self._commands_ready:
            due = time.monotonic() + self.faults.delay
            heapq.heappush(self._commands, (due, next(self._order), apply))
            self._commands_ready.notify()

    def _apply_commands(self) -> None:
        while True:
            with self._commands_ready:
                while not self._closing and (not self._commands
                                             or self._commands[0][0] > time.monotonic()):
                    wait = self._commands[0][0] - time.monotonic() if self._commands else None
                    self._commands_ready.wait(wait)
                if self._closing:
                    return
                _due, _seq, apply = heapq.heappop(self._commands)
            apply()

    def _apply_velocity(self, vx: float, vy: float, wz: float) -> None:
        if not all(math.isfinite(v) for v in (vx, vy, wz)):
            self.get_logger().warning(f"ignored a non-finite cmd_vel {(vx, vy, wz)}")
            return
        self._last_twist = time.monotonic()
        self._moving_command = bool(vx or vy or wz)
        self.sim.send_velocity(vx, vy, wz)  # ignored by the simulator unless standing

    def _apply_request(self, api_id: int, parameter: str) -> None:
        if api_id == go2_api.STOP_MOVE:
            self._moving_command = False
            self.sim.stop()
            self._record(api_id, True)
        elif api_id == go2_api.MOVE:
            try:
                move = json.loads(parameter)
                self._apply_velocity(float(move["x"]), float(move["y"]), float(move["z"]))
            except (ValueError, KeyError, TypeError) as exc:
                self._record(api_id, False, f"bad parameter {parameter!r}: {exc!r}")
                return
            self._record(api_id, True)
        elif api_id in _POSTURES or api_id in _TRICK_IDS:
            with self._busy_lock:
                self._busy += 1
            self._record(api_id, True, "queued")
            self._publish_state()  # report busy at once, as the robot acknowledges
            self._requests.put(api_id)
        else:
            self._record(api_id, False, "not simulated")

    # -- postures and tricks (the request thread; each takes seconds) -----------------------

    def _run_requests(self) -> None:
        while (api_id := self._requests.get()) is not None:
            try:
                note = self._perform(api_id)
            except RobotError as exc:
                note = f"ignored: {exc}"
            if note:
                self.get_logger().info(f"{_NAMES.get(api_id, api_id)}: {note}")
            with self._busy_lock:
                self._busy -= 1
            self._publish_state()

    def _perform(self, api_id: int) -> str:
        """Run one sport request on the simulator; a note when the robot ignored it."""
        posture = self.sim.get_state().posture
        if api_id in _POSTURES:
            needs, target = _POSTURES[api_id]
            if needs is not None and posture is not needs:
                return f"ignored: the robot is {posture.value}, not {needs.value}"
            if target is not posture:
                self.sim.set_posture(target)
            return ""
        trick = _NAMES[api_id]
        if trick not in go2_api.TRICKS:
            return "not simulated"
        self.sim.perform(trick)  # raises RobotError unless standing
        return ""

    # -- state out ---------------------------------------------------------------------------

    def _watchdog(self) -> None:
        quiet = time.monotonic() - self._last_twist
        if self._moving_command and quiet > self.settings.cmd_vel_timeout:
            self._moving_command = False
            self.sim.send_velocity(0.0, 0.0, 0.0)
            self.get_logger().info(f"cmd_vel quiet for {quiet:.2f} s: velocity set to zero",
                                   throttle_duration_sec=5.0)

    def _publish_odom(self) -> None:
        if not self.faults.odom:
            return
        st = self.sim.get_state()
        msg = Odometry()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id, msg.child_frame_id = "odom", "base_link"
        msg.pose.pose.position.x, msg.pose.pose.position.y = st.x, st.y
        msg.pose.pose.position.z = _BODY_HEIGHT[st.posture]
        msg.pose.pose.orientation.z = math.sin(st.yaw / 2.0)
        msg.pose.pose.orientation.w = math.cos(st.yaw / 2.0)
        msg.twist.twist.linear.x, msg.twist.twist.linear.y = st.vx, st.vy  # body frame
        msg.twist.twist.angular.z = st.wz
        self._odom_pub.publish(msg)

    def _publish_state(self) -> None:
        if not self.faults.states or self._closing:
            return
        st = self.sim.get_state()
        with self._busy_lock:
            busy = self._busy > 0
        mode = {Posture.SITTING: _MODE_SIT, Posture.LYING: _MODE_LIE_DOWN}.get(
            st.posture, _MODE_LOCOMOTION if st.is_moving else _MODE_BALANCE_STAND)
        c, s = math.cos(st.yaw), math.sin(st.yaw)
        self._state_pub.publish(Go2State(
            mode=_MODE_POSE if busy and st.posture is Posture.STANDING else mode,
            progress=1 if busy else 0, gait_type=1 if st.is_moving else 0,
            foot_raise_height=0.08, body_height=_BODY_HEIGHT[st.posture],
            position=[st.x, st.y, _BODY_HEIGHT[st.posture]],
            velocity=[st.vx * c - st.vy * s, st.vx * s + st.vy * c, 0.0]))  # odom frame

    def _publish_camera(self) -> None:
        if not self.faults.camera:
            return
        s = self.settings
        msg = Image(width=s.camera_width, height=s.camera_height, encoding="rgb8",
                    step=3 * s.camera_width)
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id = "camera_link"
        msg.data = scene.render(scene.DEFAULT_WORLD, self.sim.get_state().pose, s.camera_width,
                                s.camera_height)
        self._camera_pub.publish(msg)

    def _record(self, api_id: int, accepted: bool, note: str = "") -> None:
        record = {"api_id": api_id, "name": _NAMES.get(api_id, "unknown"), "accepted": accepted,
                  "note": note, "mono": time.monotonic()}
        self._record_pub.publish(String(data=json.dumps(record)))


_USAGE = f"""usage: shadowhound sim-driver [--ros-args -p NAME:=VALUE -r __ns:=/robot0 ...]

A simulated Unitree Go2 with go2_ros2_sdk's topics (cmd_vel, webrtc_req in; odom, go2_states,
camera/image_raw out) as the ROS 2 node '{NODE_NAME}'. Run a mission on it with
`shadowhound node --ros-args -p robot:=go2` in another terminal. Parameters:
{chr(10).join(f"  {n} (default {d!r}): {t}" for n, (d, t) in DRIVER_PARAMETERS.items())}
Faults: publish JSON on sim_driver/fault, e.g. '{{"odom": false}}'; '{{}}' clears them.
Exit codes: 0 after Ctrl-C / SIGTERM, 2 for invalid parameters.
"""


def main(argv: Sequence[str] | None = None) -> int:
    """`shadowhound sim-driver --ros-args ...`"""
    return run_node("shadowhound sim-driver", NODE_NAME, argv, _USAGE, SimDriver,
                    lambda driver: driver.close(),  # type: ignore[attr-defined]
                    "shutting down: the simulated robot stops")


if __name__ == "__main__":
    sys.exit(main())
