"""One simulated Go2 of `shadowhound sim-driver`: its topics, the driver's rules between them and
the robot (robot/sim_sport.py), its late odometry, its truth and its injected faults. It is
also a detector (sim_detector.py): `detections` carries what its simulated camera sees; and
with `--slam`, SLAM: odometry drifts (`--odom-drift`) and `map -> odom` on /tf corrects it.

Callbacks only hand commands over: to the command thread (which applies any injected delay),
and sport requests on to the driver's 10 Hz queue. Odometry has a thread of its own, so each
pose is published exactly `odom_delay` after it was true.

Long because: it is one simulated robot's side of the driver, whose topics share one truth,
one set of faults and its threads; what stands apart already lives apart (sim_slam, sim_detector,
sim_nav, sim_faults).
"""

from __future__ import annotations

import heapq
import itertools
import json
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from geometry_msgs.msg import Twist, Vector3
from go2_interfaces.msg import Go2State, WebRtcReq
from nav_msgs.msg import OccupancyGrid as GridMsg
from nav_msgs.msg import Odometry
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import BatteryState, Image, LaserScan
from std_msgs.msg import String

from ..robot.go2 import api as go2_api
from ..robot.go2.api import SportMode
from ..robot.go2.world_msgs import MAP_QOS, grid_to_msg, scan_to_msg
from ..robot.sim import renderer, scene, sensors
from ..robot.sim.robot import SimRobot
from ..state import Posture
from .detector import CAMERA_FOV_DEG, CocoDetector, SimDetector
from .faults import Faults, LyingOdometry
from .nav import SimNavigator
from .options import DriverSettings
from .slam import Pose, SimSlam
from .sport import SimSportMode, Truth
from .unitree import UnitreeLink

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = ["Faults", "SimGo2", "Truth"]

_RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
_SENSOR = QoSProfile(
    depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
_NAMES = {
    go2_api.MOVE: "Move",
    go2_api.STOP_MOVE: "StopMove",
    **{c.api_id: c.name for c in go2_api.POSTURE_CHANGES.values()},
    **{
        t.api_id: t.name for t in go2_api.TRICKS.values() if t.api_id not in go2_api.POSTURE_CHANGES
    },
}


class SimGo2:
    """One robot's topics on the driver node, with `prefix` ('' or 'robot{i}/')."""

    def __init__(self, node: Node, settings: DriverSettings, prefix: str, sim: SimRobot) -> None:
        self.node, self.settings, self.prefix, self.sim = node, settings, prefix, sim
        self.body = SimSportMode(
            sim,
            move_timeout=settings.move_timeout,
            posture_seconds=settings.posture_seconds,
            start=Posture(settings.start_posture),
            stand_up_mode=SportMode(settings.stand_up_mode),
        )
        self.faults = Faults()
        self._lying = LyingOdometry()  # odometry faults that fire on the way (sim_faults)
        self._lie_lock = threading.Lock()
        self._counts = {"twists": 0, "twists_dropped": 0, "requests_dropped": 0, "detections": 0}
        self._pending: deque[tuple[int, Any, str, float]] = deque()  # the 10 Hz queue
        self._states: deque[tuple[float, Truth, int]] = deque()  # go2_states on their way
        self._commands: list[tuple[float, int, Callable[[], None]]] = []  # (due, seq, apply)
        self._order = itertools.count()
        self._ready = threading.Condition()
        self._closing = threading.Event()
        self._stalled_until = 0.0  # monotonic: the `stall_ms` fault holds commands and odometry
        # go2_ros2_sdk's topics, or unitree_ros2's (unitree.py) with --interface unitree_ros2
        sdk = settings.interface == "go2_ros2_sdk"
        self.unitree = None if sdk else UnitreeLink(node, self.topic, self._on_unitree_request)
        self._odom_pub = (
            node.create_publisher(Odometry, self.topic("odom"), _RELIABLE) if sdk else None
        )
        self._slam = SimSlam(node, settings.slam, settings.odom_drift)
        self._state_pub = (
            node.create_publisher(Go2State, self.topic("go2_states"), _RELIABLE) if sdk else None
        )
        self._camera_pub = (
            node.create_publisher(Image, self.topic("camera/image_raw"), _SENSOR)
            if settings.camera_rate_hz > 0
            else None
        )
        self._truth_pub = node.create_publisher(String, self.topic("sim_driver/truth"), _RELIABLE)
        self._record_pub = node.create_publisher(
            String, self.topic("sim_driver/requests"), QoSProfile(depth=50)
        )
        self._battery_pub = (
            node.create_publisher(BatteryState, self.topic(settings.battery_topic), _RELIABLE)
            if settings.battery is not None and sdk
            else None
        )
        self._scan_pub = (
            node.create_publisher(LaserScan, self.topic("scan"), _SENSOR)
            if settings.scan_rate_hz > 0
            else None
        )
        boxes, info = self.topic("detected_objects"), self.topic("camera/camera_info")
        width, height = settings.camera_width, settings.camera_height
        self.detector = (
            SimDetector.create(node, self.topic("detections"), "map" if settings.slam else "odom")
            if settings.detector == "shadowhound"
            else CocoDetector.create(node, boxes, info, width, height, CAMERA_FOV_DEG)
            if settings.detector == "coco"
            else None
        )
        if settings.map:  # published once: transient local keeps it for late subscribers
            self._map_pub = node.create_publisher(GridMsg, self.topic("map"), MAP_QOS)
            frame = "map" if settings.slam else "odom"  # SLAM's map is in its own frame
            self._map_pub.publish(
                grid_to_msg(
                    sensors.scene_grid(sim.map_world), frame, node.get_clock().now().to_msg()
                )
            )
        self.navigator = (
            SimNavigator(
                node,
                self.prefix + "navigate_to_pose",
                self.body,
                self.drive,
                settings.nav_speed,
                (lambda: self._slam.true_map_odom(self.body.truth())) if settings.slam else None,
            )
            if settings.navigate_to_pose
            else None
        )
        if sdk:
            node.create_subscription(Twist, self.topic("cmd_vel_out"), self._on_twist, _RELIABLE)
            node.create_subscription(
                WebRtcReq, self.topic("webrtc_req"), self._on_request, _RELIABLE
            )
        node.create_subscription(String, self.topic("sim_driver/fault"), self._on_fault, _RELIABLE)
        self._threads = [
            threading.Thread(
                target=self._apply_commands, daemon=True, name=f"sim-commands-{prefix}"
            ),
            threading.Thread(target=self._run_odometry, daemon=True, name=f"sim-odometry-{prefix}"),
        ]

    def topic(self, name: str) -> str:
        return self.node.resolve_topic_name(self.prefix + name)

    def start(self) -> None:
        for thread in self._threads:
            thread.start()

    def close(self) -> None:
        self._closing.set()
        with self._ready:
            self._ready.notify()
        if self.navigator is not None:
            self.navigator.close()
        self.body.close()
        for thread in self._threads:
            thread.join(2.0)

    # -- commands in -----------------------------------------------------------------------

    def _on_twist(self, msg: Twist) -> None:
        if not self.faults.drop_commands:
            x, y, z = msg.linear.x, msg.linear.y, msg.angular.z
            self._schedule(lambda: self._apply_twist(x, y, z))

    def drive(self, x: float, y: float, z: float) -> None:
        """Velocity from the navigate_to_pose server: as a Twist on cmd_vel_out would come."""
        self._on_twist(Twist(linear=Vector3(x=float(x), y=float(y)), angular=Vector3(z=float(z))))

    def _apply_twist(self, x: float, y: float, z: float) -> None:
        self._counts["twists"] += 1
        move = go2_api.move_parameter(x, y, z)
        if move is None:  # go2_ros2_sdk drops an all-zero Twist: it stops nothing
            self._counts["twists_dropped"] += 1
            return
        self.body.move(move["x"], move["y"], move["z"])

    def _on_request(self, msg: WebRtcReq) -> None:
        api_id, text, topic = int(msg.api_id), str(msg.parameter), str(msg.topic)
        if self.faults.drop_commands:
            self._record(api_id, time.monotonic(), None, False, "lost (fault injection)")
        else:
            self._schedule(lambda: self._accept_request(api_id, text, topic))

    def _accept_request(self, api_id: int, text: str, topic: str) -> None:
        arrived = time.monotonic()
        try:
            parameter = "" if text == "" else json.loads(text)
        except ValueError as exc:  # the driver logs "Invalid JSON" and drops the request
            self._counts["requests_dropped"] += 1
            self._record(
                api_id,
                arrived,
                None,
                False,
                f"dropped by the driver: parameter is not JSON ({exc})",
            )
            return
        self._pending.append((api_id, parameter, topic or go2_api.SPORT_TOPIC, arrived))

    def _on_unitree_request(
        self, api_id: int, text: str, answer: Callable[[bool, str], None]
    ) -> None:
        """A unitree_api Request: straight to the robot (no driver's queue between)."""
        if self.faults.drop_commands:
            self._record(api_id, time.monotonic(), None, False, "lost (fault injection)")
            return

        def act() -> None:
            arrived = time.monotonic()
            report = self._reporter(api_id, arrived, arrived)
            try:
                parameter = "" if text == "" else json.loads(text)
            except ValueError as exc:
                report(False, f"ignored: parameter is not JSON ({exc})")
                answer(False, f"parameter is not JSON ({exc})")
                return

            def both(accepted: bool, note: str) -> None:
                report(accepted, note)
                answer(accepted, note)

            self.body.request(api_id, parameter, go2_api.SPORT_TOPIC, both)

        self._schedule(act)

    def forward_requests(self) -> None:
        """The driver's 10 Hz loop: every queued request goes to the robot, in order."""
        if time.monotonic() < self._stalled_until:
            return  # the process is stalled (fault injection)
        while self._pending:
            api_id, parameter, topic, arrived = self._pending.popleft()
            self.body.request(
                api_id, parameter, topic, self._reporter(api_id, arrived, time.monotonic())
            )

    def _reporter(self, api_id: int, arrived: float, sent: float) -> Callable[[bool, str], None]:
        return lambda accepted, note: self._record(api_id, arrived, sent, accepted, note)

    def _on_fault(self, msg: String) -> None:
        try:
            faults = Faults.from_json(msg.data)
        except ValueError as exc:  # json.JSONDecodeError is a ValueError
            self.node.get_logger().warning(f"ignored a fault message {msg.data!r}: {exc}")
            return
        t = self.body.truth()
        with self._lie_lock:
            self.faults = faults
            self._lying.arm(faults, (t.x, t.y, t.yaw))
        self.node.get_logger().warning(f"{self.prefix}fault injection now: {faults}")

    def _schedule(self, apply: Callable[[], None]) -> None:
        with self._ready:
            heapq.heappush(
                self._commands, (time.monotonic() + self.faults.delay, next(self._order), apply)
            )
            self._ready.notify()

    def _apply_commands(self) -> None:
        while True:
            with self._ready:
                while not self._closing.is_set() and (
                    not self._commands
                    or max(self._commands[0][0], self._stalled_until) > time.monotonic()
                ):
                    due = max(self._commands[0][0], self._stalled_until) if self._commands else 0
                    self._ready.wait(due - time.monotonic() if self._commands else None)
                if self._closing.is_set():
                    return
                _due, _seq, apply = heapq.heappop(self._commands)
            apply()

    def _record(
        self, api_id: int, arrived: float, sent: float | None, accepted: bool, note: str
    ) -> None:
        record = {
            "api_id": api_id,
            "name": _NAMES.get(api_id, "unknown"),
            "accepted": accepted,
            "note": note,
            "mono": arrived,
            "sent": sent,
            "acted": time.monotonic(),
        }
        self._record_pub.publish(String(data=json.dumps(record)))

    # -- state out -------------------------------------------------------------------------

    def _run_odometry(self) -> None:
        """Take the true pose every period (as the faults show it); publish each one
        `odom_delay` later, in bursts of `odom_burst`: a burst waits for its last sample."""
        period, delay = 1.0 / self.settings.odom_rate_hz, self.settings.odom_delay
        Taken = tuple[Truth, tuple[float, float, float] | None, float, Pose]
        due: deque[tuple[float, Taken]] = deque()
        group: list[Taken] = []  # the burst being gathered
        next_take = time.monotonic()
        while True:
            if self._closing.wait(max(0.0, self._stalled_until - time.monotonic())):
                return  # a stalled process takes and publishes nothing (fault injection)
            now = time.monotonic()
            if now >= next_take:
                truth = self.body.truth()
                odom = self._slam.odometer.update((truth.x, truth.y, truth.yaw))
                with self._lie_lock:
                    before = self._lying.fired
                    shown, shift = self._lying.publish(odom)
                    fired = self._lying.fired and not before
                    fall = fired and self._lying.faults.fall
                    if fired and self._lying.faults.stall:
                        self._stalled_until = now + self._lying.faults.stall
                if fall:
                    self.body.fall()
                group.append((truth, shown, shift, odom))
                if len(group) >= self.settings.odom_burst:  # it all goes when its last is due
                    due.extend((now + delay, taken) for taken in group)
                    group.clear()
                next_take = max(next_take + period, now)
            while due and due[0][0] <= time.monotonic():
                truth, shown, shift, odom = due.popleft()[1]
                if self.faults.odom:
                    self._publish_odom(truth, shown, shift, odom)
            wake = min(next_take, due[0][0]) if due else next_take
            if self._closing.wait(max(0.0, wake - time.monotonic())):
                return

    def _publish_odom(
        self, t: Truth, shown: tuple[float, float, float] | None, shift: float, odom: Pose
    ) -> None:
        """Odometry of the true `t` as the faults show it: `shown` (None: NaN), the stamp
        `shift` seconds off; and on /tf odom -> base_link (as the driver broadcasts it) and,
        with --slam, SLAM's map -> odom of the same moment (the truth over the drifting
        `odom`, off by any `slam_error`)."""
        if self._odom_pub is None:  # unitree_ros2: the pose is in SportModeState
            return
        msg = Odometry()  # pose only: go2_ros2_sdk never fills the twist
        stamp = self.node.get_clock().now().nanoseconds + int(shift * 1e9)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(max(0, stamp), 1_000_000_000)
        msg.header.frame_id = "odom"
        msg.child_frame_id = f"{self.prefix}base_link"
        x, y, yaw = shown if shown is not None else (math.nan, math.nan, math.nan)
        msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
        msg.pose.pose.position.z = t.body_height
        msg.pose.pose.orientation.z = math.sin(yaw / 2.0)
        msg.pose.pose.orientation.w = math.cos(yaw / 2.0)
        self._odom_pub.publish(msg)
        if shown is not None:
            self._slam.publish(msg.header.stamp, msg.child_frame_id, t, shown, odom, self.faults)

    def publish_state(self) -> None:
        """go2_states as the robot was `odom_delay` ago: the driver reads it from the same
        state stream as odometry, over the same link."""
        if self._closing.is_set():
            return
        now = time.monotonic()
        self._states.append((now, self.body.truth(), self.body.progress))
        shown = None
        while self._states and self._states[0][0] <= now - self.settings.odom_delay:
            shown = self._states.popleft()
        if shown is None or not self.faults.states:
            return
        _taken, t, progress = shown
        if self.unitree is not None:
            if self.faults.odom:  # unitree_ros2 has no odom: the sport state carries the pose
                self.unitree.publish_state(t, progress)
            return
        assert self._state_pub is not None
        c, s = math.cos(t.yaw), math.sin(t.yaw)
        standing = t.posture is Posture.STANDING and not t.changing
        self._state_pub.publish(
            Go2State(
                mode=t.mode,
                progress=progress,
                gait_type=1 if t.mode == SportMode.LOCOMOTION else 0,
                foot_raise_height=0.08 if standing else 0.0,
                position=[t.x, t.y, t.body_height],
                body_height=t.body_height,
                velocity=[t.vx * c - t.vy * s, t.vx * s + t.vy * c, 0.0],
            )
        )  # odom frame

    def battery_level(self, t: Truth) -> float | None:
        """Percent left: the set start less what the simulator has drained since."""
        start = self.settings.battery
        return None if start is None else max(0.0, start - (100.0 - t.battery))

    def publish_battery(self) -> None:
        t = self.body.truth()
        level = self.battery_level(t)
        if self.unitree is not None:  # LowState always carries the charge
            self.unitree.publish_low_state(t.battery if level is None else level)
            return
        if self._battery_pub is None or level is None:
            return
        msg = BatteryState(
            percentage=level / 100.0,
            present=True,
            voltage=math.nan,
            power_supply_status=BatteryState.POWER_SUPPLY_STATUS_DISCHARGING,
        )
        msg.header.stamp = self.node.get_clock().now().to_msg()
        self._battery_pub.publish(msg)

    def truth_dict(self) -> dict[str, Any]:
        stamp = self.node.get_clock().now().nanoseconds / 1e9
        t = self.body.truth()
        return {
            **t.to_dict(),
            "stamp": stamp,
            "robot": self.prefix.rstrip("/") or "",
            "battery": self.battery_level(t),
            "faults": {**self.faults.to_dict(), "fired": self._lying.fired},
            **self._counts,
            "navigation": self.navigator.truth() if self.navigator else None,
            **self._slam.published,
        }

    def publish_truth(self) -> None:
        if not self._closing.is_set():
            self._truth_pub.publish(String(data=json.dumps(self.truth_dict())))

    def publish_scan(self) -> None:
        scan = self.sim.get_scan()
        if self._scan_pub is None or self._closing.is_set() or scan is None:
            return
        msg = scan_to_msg(
            scan,
            f"{self.prefix}base_link",
            self.node.get_clock().now().to_msg(),
            1.0 / self.settings.scan_rate_hz,
        )
        self._scan_pub.publish(msg)

    def publish_detections(self) -> None:
        """What the simulated camera sees now, as a detector reports it (sim_detector.py);
        nothing while the camera fault is on."""
        if self.detector is None or not self.faults.camera or self._closing.is_set():
            return
        self.detector.publish(self.sim.world, self.sim.get_state().pose)
        self._counts["detections"] += 1

    def publish_camera(self) -> None:
        if not self.faults.camera or self._camera_pub is None:
            return
        s = self.settings
        msg = Image(
            width=s.camera_width, height=s.camera_height, encoding="rgb8", step=3 * s.camera_width
        )
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.header.frame_id = f"{self.prefix}camera_link"
        msg.data = renderer.render(
            scene.DEFAULT_WORLD, self.sim.get_state().pose, s.camera_width, s.camera_height
        )
        self._camera_pub.publish(msg)
