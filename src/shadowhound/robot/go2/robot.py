"""Go2RosRobot: a Unitree Go2 driven through go2_ros2_sdk's ROS 2 topics (the Robot protocol).

Written against how the driver really behaves (docs/go2.md):

- motion: geometry_msgs/Twist, capped, re-published at 10 Hz while non-zero (the robot drops
  a Move after about a second). The topic follows the graph: `cmd_vel` when a relay
  (twist_mux: one node subscribing `cmd_vel` and publishing `cmd_vel_out`) carries it to the
  driver, else `cmd_vel_out`, which the driver itself listens on, both relative to the
  namespace, looked at again when the graph changes (go2_topics); or the one configured.
- stopping: every stop (end of a step, settle, stall, cancel, e-stop, close) sends StopMove
  (sport api 1003). The driver drops all-zero Twists, so a zero Twist is never sent.
- state: odometry carries the pose only and arrives late; `MotionTracker` predicts the pose
  now from what was commanded since, and reports the robot still only once odometry shows it
  still. Odometry older than `odom_timeout` while motion is under way makes `get_state` raise
  RobotError (after a stop the last state is returned with `connected` False).
- posture: from `go2_states` (mode and body height, read through go2_api's one table), at start
  and after each posture command; a posture command is done when the posture is reached
  (`progress` is no help: it stays 0 while postures run). No command when already there.
  Standing up, BalanceStand follows StandUp once the body height shows standing, whatever the
  mode (firmware differ), or after a bounded wait; the stand ends once the robot walks, and a
  walk on a robot standing with its joints held balances it first.
- battery: a sensor_msgs/BatteryState topic when one is configured and publishing, else
  unknown (None): the driver publishes no battery level.
- camera: `camera/image_raw` (sensor_msgs/Image) or a topic ending in `compressed`.
- map: nav_msgs/OccupancyGrid on `map` (slam_toolbox, map_server; transient local), read into
  the core's grid with its origin and resolution: `belief()`. No map: `belief()` is None and
  paths are straight lines.
- frames (TF): `/tf` and `/tf_static` (tf2_msgs/TFMessage) into a TfTree (tf_tree.py), only
  the edges it is asked about (into odometry's frame, `odom` and `base_link`): the body's links
  that robot_state_publisher sends at 50 Hz are dropped unread. When SLAM publishes `map ->
  odom` (`map_frame`), the robot's world is the map: `get_state` poses, taught places,
  sightings, the map and Nav2 goals are in it (odometry carried over with the latest map ->
  odom); a correction larger than a leg may absorb (a jump) counts in `RobotState.relocalized`,
  and the running leg stops (a walk plans again). Without it the world is odometry's frame, and
  a map in another frame is used as if the two coincided, with a warning. A transform stamped
  beyond the window of this computer's clock (go2/stamps.py) is refused and reported.
- inputs: every subscription reads within its kind's size (ros_inputs.py, input_limits.py);
  maps, images, boxes, detections and TF are read on threads of their own, not on the executor
  thread that reads odometry; what was refused or cut is `input_problems` (the diagnostics').
- scan: sensor_msgs/LaserScan on `scan`, taken at the pose odometry gave when it arrived.
- navigation: Nav2's NavigateToPose on `navigate_to_pose` (`navigator()`, go2_nav2.py);
  `stop` and `emergency_stop` cancel its goals.
- detections (optional, `detections_topic`): shadowhound_interfaces/DetectionArray from any
  detector; each detection becomes a sighting (`known_objects()`), see go2_detections.py.
- boxes (optional, `coco_detections_topic`): vision_msgs/Detection2DArray from a 2-D detector
  (go2_ros2_sdk's coco_detector, `detected_objects`), placed with `camera_info_topic`'s K, the
  camera's mount, odometry and the scan at the image's stamp (go2_detections.BoxIntake).
- voice: `say` publishes one std_msgs/String on `speech_topic` (go2_ros2_sdk's `tts_node`
  listens on `/tts` and plays it on the robot's speaker), without waiting for it to be heard.

What every Go2 over ROS has (its own rclpy node and executor thread, so it works inside the
MissionNode process or in a plain script; the locks, stops, the e-stop latch, the state) is
ros_base.py's RosRobot, as the Go2 EDU's is.

Long because: it is the one Robot implementation over go2_ros2_sdk, whose protocol methods and
ROS callbacks share one node, one executor thread and one lock; what needs no ROS already
lives apart (go2_api: the sport API table, go2_motion: odometry tracking, go2_posture, the
detections' and the inputs' rules).
"""

from __future__ import annotations

import contextlib
import json
import math
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any, TypeAlias

from geometry_msgs.msg import Twist
from go2_interfaces.msg import Go2State, WebRtcReq
from nav_msgs.msg import OccupancyGrid as GridMsg
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import BatteryState, CameraInfo, CompressedImage, Image, LaserScan
from std_msgs.msg import String

from ...camera import raw_image_frame, to_camera_frame
from ...errors import TransformUnavailable
from ...robot_config import Go2RobotSettings
from ...state import CameraFrame, Pose2D, Posture, Scan, Sighting, compose, normalize_angle
from ...world import Belief, GridError, merge_sightings
from ...world.image_sighting import Bearing, SightingRules
from ...world.objects import KnownObject
from ..base import RobotError
from ..estop_listener import EstopListener
from ..ros_base import DRIVEN_SETTLE, KEEPALIVE_PERIOD, RELIABLE, RosRobot
from ..ros_inputs import RosInputs
from ..tf_tree import BASE, ODOM, MapCorrection, TfTree, Transform2D
from . import api as go2_api
from .detections import (
    COCO_CLASSES,
    HOLD_SECONDS,
    BoxIntake,
    CameraMount,
    Frames,
    SightingBoard,
    sightings_from_msg,
)
from .motion import MAX_LATENCY
from .nav2 import Nav2Navigator
from .odometry import OdometryFault
from .posture import STAND_UP_BOUND, capped, finite_velocity, trick_info
from .topics import VELOCITY_TOPICS, VelocityRoute, choose_velocity_topic, node_name
from .world_msgs import MAP_QOS, grid_from_msg, scan_from_msg

_SENSOR = QoSProfile(
    depth=1, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
_SENSOR_DEPTH = QoSProfile(
    depth=10, history=HistoryPolicy.KEEP_LAST, reliability=ReliabilityPolicy.BEST_EFFORT
)
# tf2's own QoS: /tf reliable, depth 100; /tf_static transient local (late joiners get it).
_TF = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
_TF_STATIC = QoSProfile(
    depth=100,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
_PUBLISHERS_PERIOD = 0.5  # seconds between looks for a second odometry publisher
_LOOK_SECONDS = 1.5  # longest wait for the detector's report on a view (2 Hz detectors, DDS)
IN_VIEW_SECONDS = HOLD_SECONDS + 0.5  # robot seconds a detection counts as in view now: a box
# seen while turning waits (up to HOLD_SECONDS) for the odometry of its image's time


# The Go2's settings: the profile's `robot: {type: go2, ...}` (robot_config.Go2RobotSettings).
Go2RosConfig: TypeAlias = Go2RobotSettings


class Go2RosRobot(RosRobot[Go2RobotSettings]):
    """The Robot protocol over go2_ros2_sdk. A real robot: on the wall clock (BaseRobot's)."""

    pose_source = "odometry"

    def __init__(
        self, config: Go2RosConfig | None = None, *, context: Context | None = None
    ) -> None:
        c = config or Go2RosConfig()
        super().__init__(
            c,
            context,
            name="go2",
            description="Go2 over ROS",
            pose_latency=c.odom_latency,
            pose_timeout=c.odom_timeout,
        )
        self.tricks = go2_api.offered(ai_mode=c.firmware_tricks)
        self._detections_at: float | None = None  # monotonic receipt of the last detections
        self._frame: CameraFrame | None = None
        self._sightings = SightingBoard()
        self._boxes = (
            BoxIntake(
                CameraMount(c.camera_x, c.camera_y, c.camera_yaw),
                SightingRules(max_range=c.coco_max_range),
            )
            if c.coco_detections_topic
            else None
        )
        self._frames = Frames()  # odometry's own frame ids replace these when it arrives
        self._odom_frame = "odom"  # odometry's header.frame_id, once it arrives
        self._tf = TfTree()  # /tf and /tf_static; read and fed under self._lock
        self._map_odom: Transform2D | None = None  # SLAM's latest map -> odom
        self._map_odom_stamp = -math.inf
        self._relocalized = 0  # map -> odom jumps seen (RobotState.relocalized)
        self._jumps: tuple[float, float, float] = (0.0, 0.0, 0.0)  # composed (RobotState)
        self._map: Belief | None = None  # the latest map, inflated once per map
        self._scan: tuple[float, Scan] | None = None  # (receipt, scan)
        self._last_sent = 0.0
        self._route: VelocityRoute | None = None  # where velocity goes (discovered)
        self._open_node("Go2")
        self._navigator = (
            Nav2Navigator(self.node, c.nav2_action, self._executor.create_task)
            if c.nav2_action
            else None
        )
        self._estop_listeners: list[Callable[[bool], None]] = []
        self._estop_node = (
            EstopListener(
                f"{c.node_name}_estop",
                "/",
                self._context,
                RELIABLE,
                estop_topic=c.estop_topic,
                release_topic=c.estop_release_topic,
                on_estop=self._estop_pressed,
                on_release=self._estop_released,
            )
            if c.estop_topic
            else None
        )
        self._start_spinning("go2-ros")

    def _build_interfaces(self) -> None:
        c, n = self.config, self.node
        names = [c.cmd_vel_topic] if c.cmd_vel_topic else list(VELOCITY_TOPICS)
        self._twist_pubs = {name: n.create_publisher(Twist, name, RELIABLE) for name in names}
        self._request_pub = n.create_publisher(WebRtcReq, c.webrtc_topic, RELIABLE)
        self._speech_pub = (
            n.create_publisher(String, c.speech_topic, RELIABLE) if c.speech_topic else None
        )
        # Every input within its size (input_limits); maps, images, detections and TF read
        # off the executor thread, which odometry and the stops need (ros_inputs).
        self._inputs = inputs = RosInputs(n)
        sub = inputs.subscribe
        sub(Odometry, c.odom_topic, self._on_odom, RELIABLE, "small")
        sub(Go2State, c.state_topic, self._on_state, RELIABLE, "small")
        if c.battery_topic:
            sub(BatteryState, c.battery_topic, self._on_battery, RELIABLE, "small")
        if c.camera_topic:
            compressed = c.camera_topic.rstrip("/").endswith("compressed")
            sub(
                CompressedImage if compressed else Image,
                c.camera_topic,
                self._on_compressed if compressed else self._on_image,
                _SENSOR,
                "image",
                thread="go2-camera",
            )
        if c.detections_topic:
            try:
                from shadowhound_interfaces.msg import DetectionArray
            except ImportError as exc:
                raise RobotError(
                    "detections_topic needs the shadowhound_interfaces package: "
                    f"run scripts/build_ros.sh ({exc})"
                ) from exc
            sub(
                DetectionArray,
                c.detections_topic,
                self._on_detections,
                RELIABLE,
                "detections",
                thread="go2-detections",
            )
        if c.coco_detections_topic:
            try:
                from vision_msgs.msg import Detection2DArray
            except ImportError as exc:
                raise RobotError(
                    "coco_detections_topic needs the vision_msgs package: "
                    f"run scripts/build_ros.sh ({exc})"
                ) from exc
            # Best effort matches a detector's reliable publisher and a best-effort one.
            sub(
                Detection2DArray,
                c.coco_detections_topic,
                self._on_boxes,
                _SENSOR_DEPTH,
                "detections",
                thread="go2-boxes",
            )
            sub(CameraInfo, c.camera_info_topic, self._on_camera_info, _SENSOR, "small")
        if c.map_topic:  # reading and inflating a large map takes seconds
            sub(GridMsg, c.map_topic, self._take_map, MAP_QOS, "map", thread="go2-map")
        if c.map_frame:
            try:
                from tf2_msgs.msg import TFMessage
            except ImportError as exc:
                raise RobotError(
                    "reading SLAM's map frame from /tf needs the tf2_msgs package: run "
                    f"scripts/build_ros.sh, or set map_frame to '' to read no TF ({exc})"
                ) from exc
            # In order, off the executor: robot_state_publisher's 30 links take ms to read.
            sub(TFMessage, "/tf", self._on_tf, _TF, "tf", thread="go2-tf", depth=_TF.depth)
            sub(
                TFMessage,
                "/tf_static",
                self._on_tf_static,
                _TF_STATIC,
                "tf",
                thread="go2-tf-static",
                depth=_TF_STATIC.depth,
            )
        if c.scan_topic:
            sub(LaserScan, c.scan_topic, self._on_scan, _SENSOR, "scan")
        n.create_timer(KEEPALIVE_PERIOD, self._keep_alive)
        n.create_timer(5.0, self._warn_without_odometry)
        n.create_timer(_PUBLISHERS_PERIOD, self._check_publishers)

    @property
    def velocity_topic(self) -> str:
        """The full name of the topic velocity goes to (discovered unless configured)."""
        return self.topic(self._discover_velocity_topic())

    @property
    def joints_held(self) -> bool:
        """go2_states shows the robot standing in a mode in which it does not walk (after a
        StandUp: JointLock, or Damping on some firmware), recently and settled."""
        report = self._postures.fresh()
        return report is not None and report.posture is Posture.STANDING and not report.balanced

    @property
    def odom_latency(self) -> float:
        """Seconds odometry lags the robot, as configured or as measured."""
        with self._lock:
            return self._tracker.latency

    @property
    def walking_mode(self) -> bool:
        """go2_states shows the robot standing in a mode in which it obeys Moves (settled)."""
        return self._postures.balanced()

    # -- callbacks (the executor thread, short; or a reading thread: ros_inputs) ----------

    def _on_odom(self, msg: Odometry) -> None:
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        now = time.monotonic()
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        if self._navigator is not None and self._navigator.driving:
            self._body.driven_until = now + DRIVEN_SETTLE + self.odom_latency
        elsewhere = now < self._body.driven_until
        with self._lock:
            before = self._tracker.latency
            fault = self._intake.receive(now, stamp, p.x, p.y, yaw, driven_elsewhere=elsewhere)
            self._pose_at = now
            after = self._tracker.latency
            self._odom_frame = msg.header.frame_id or self._odom_frame
            if msg.header.frame_id and msg.child_frame_id:
                self._frames = Frames(
                    msg.header.frame_id.lstrip("/"), msg.child_frame_id.lstrip("/")
                )
        if fault is not None:
            self._odometry_fault(fault)
        elif self._boxes is not None:  # the pose was the robot's `after` seconds before its stamp
            problem = self._boxes.on_pose(stamp - after, Pose2D(p.x, p.y, yaw), self._ros_now())
            if problem is not None:
                topic = self.topic(self.config.odom_topic)
                self._inputs.refuse(topic, "stamp", f"a pose {problem}: not used to place boxes")
        if abs(after - before) >= 0.01:
            self.node.get_logger().info(f"odometry lags the robot by {after:.2f} s (measured)")

    def _odometry_fault(self, fault: OdometryFault) -> None:
        """Odometry stopped being believable: stop at once if moving; `get_state` raises
        until it is trusted again, so the step fails naming the fault and no new one starts."""
        with self._lock:
            moving = not self._halted
        if moving:
            self.stop()
        self.node.get_logger().warning(
            f"odometry on {self.topic(self.config.odom_topic)} is not trusted: {fault.message}"
            + ("; the robot was stopped" if moving else ""),
            throttle_duration_sec=1.0,
        )

    def _check_publishers(self) -> None:
        """Exactly one node may publish odometry: two (two SDKs on one network, go2_ros2_sdk
        #28) interleave two frames."""
        topic = self.topic(self.config.odom_topic)
        try:
            infos = self.node.get_publishers_info_by_topic(topic)
        except Exception:  # rclpy raises several types once the context is shutting down
            return
        names = sorted({f"{i.node_namespace.rstrip('/')}/{i.node_name}" for i in infos})
        problem = (
            f"{len(infos)} publishers of odometry on {topic} ({', '.join(names)}): two SDKs or "
            "drivers on one network? Only one may publish it (go2_ros2_sdk #28)"
            if len(infos) > 1
            else None
        )
        with self._lock:
            fault = self._intake.report("publishers", problem, time.monotonic())
        if fault is not None:
            self._odometry_fault(fault)

    def _on_state(self, msg: Go2State) -> None:
        self._observe_posture(int(msg.mode), float(msg.body_height))

    def _on_tf(self, msg: Any) -> None:
        self._take_transforms(msg, static=False)

    def _on_tf_static(self, msg: Any) -> None:
        self._take_transforms(msg, static=True)

    def _take_transforms(self, msg: Any, static: bool) -> None:
        """Feed the frames' tree; when SLAM's map -> odom moves the robot's map pose by more
        than a leg may absorb, count a relocalization (a running leg stops on it).

        Only edges into the frames the tree is asked about go in: odometry's frame (SLAM's
        map -> odom, `_to_world`), and `odom` and `base_link` (TfTree.map_to_odom_jump measures
        a correction at the robot). The rest (robot_state_publisher's dozens of links, at
        50 Hz) is dropped here, before the lock."""
        # A reference read without the lock: a frame id changing meanwhile is read again below.
        wanted = (self._odom_frame, ODOM, BASE)
        log = self.node.get_logger()
        now = self._ros_now()  # stamps beyond TfTree's window around it are refused
        for t in msg.transforms:
            child = str(t.child_frame_id).lstrip("/")
            if child not in wanted:
                continue
            parent = str(t.header.frame_id).lstrip("/")
            q, p = t.transform.rotation, t.transform.translation
            yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
            stamp = t.header.stamp.sec + t.header.stamp.nanosec * 1e-9
            edge = Transform2D(float(p.x), float(p.y), yaw)
            try:
                with self._lock:
                    if static:
                        self._tf.set_static(parent, child, edge)
                    else:
                        self._tf.set_transform(parent, child, stamp, edge, now=now)
                    slam = parent == self.config.map_frame and child == self._odom_frame
                    first, jump = self._take_map_odom(stamp, edge) if slam else (False, None)
            except TransformUnavailable as exc:
                topic = "/tf_static" if static else "/tf"
                self._inputs.refuse(topic, f"{parent} -> {child}", f"ignored: {exc}")
                continue
            if first:
                log.info(
                    f"SLAM's {parent} -> {child} on /tf: poses, places, objects and Nav2 goals "
                    f"are in {parent!r} now"
                )
            if jump is not None:
                log.warning(
                    f"SLAM corrected the robot's map pose by {jump.distance:.2f} m and "
                    f"{math.degrees(jump.yaw):.0f} degrees ({parent} -> {child}): a leg under "
                    "way stops (a walk plans again from the corrected pose)"
                )

    def _take_map_odom(self, stamp: float, edge: Transform2D) -> tuple[bool, MapCorrection | None]:
        """SLAM's newest map -> odom (older ones only fill the history): (whether it is the
        first, the correction since the last one when it is a jump). With self._lock held."""
        if stamp < self._map_odom_stamp:
            return False, None
        first = self._map_odom is None
        jump = None if first else self._tf.map_to_odom_jump(self._map_odom_stamp)
        self._map_odom, self._map_odom_stamp = edge, stamp
        if jump is not None:  # the map moved by after * before^-1 under the robot
            moved = jump.after.compose(jump.before.inverse())
            self._relocalized += 1
            self._jumps = compose((moved.x, moved.y, moved.yaw), self._jumps)
        return first, jump

    def _to_world(self, x: float, y: float, yaw: float, stamp: float | None = None) -> Pose2D:
        """A pose in odometry's frame in the robot's world frame: the map once SLAM's map ->
        odom is known (at `stamp`, ROS time, when the history holds it; else the latest).
        Call with self._lock held."""
        pose = Pose2D(x, y, yaw)
        if self._map_odom is None:
            return pose
        if stamp is not None:
            with contextlib.suppress(TransformUnavailable):
                return self._tf.lookup(self.config.map_frame, self._odom_frame, stamp).apply(pose)
        return self._map_odom.apply(pose)

    @property
    def world_frame(self) -> str:
        """The frame poses, places, objects and goals are in: SLAM's map once map -> odom
        has arrived, else odometry's frame."""
        with self._lock:
            return self.config.map_frame if self._map_odom is not None else self._odom_frame

    def _take_map(self, msg: GridMsg) -> None:
        """On the map thread (the newest map first; ros_inputs)."""
        log = self.node.get_logger()
        try:
            grid = grid_from_msg(msg)
        except GridError as exc:
            self._inputs.refuse(self.topic(self.config.map_topic), "map", f"ignored a map: {exc}")
            return
        world = self.world_frame
        frame = msg.header.frame_id
        if frame and frame.lstrip("/") != world.lstrip("/"):
            log.warning(
                f"the map is in frame {frame!r}, poses in {world!r}: without "
                f"{frame.lstrip('/')} -> {world} on /tf they are taken as one frame (right "
                "while odometry has not drifted from the map; see docs/go2-stack.md)",
                throttle_duration_sec=60.0,
            )
        with self._lock:
            belief = self._map
        if belief is not None:  # the same world model: the objects known stay
            belief.replace_grid(grid)  # inflated here, off the mission's thread
        else:
            belief = Belief(grid, self._sightings.objects(), self.config.robot_radius)
            _ = belief.inflated  # inflated once here, off the mission's thread
            with self._lock:
                self._map = belief
        log.info(
            f"map {grid.width} x {grid.height} at {grid.resolution:g} m from "
            f"{self.topic(self.config.map_topic)}",
            throttle_duration_sec=30.0,
        )

    def _on_scan(self, msg: LaserScan) -> None:
        now = time.monotonic()
        with self._lock:
            pose = self._tracker.pose(now)
            world = self._to_world(*pose)
        topic = self.topic(self.config.scan_topic)
        try:
            scan = scan_from_msg(msg, Pose2D(*pose), now)
        except ValueError as exc:
            self._inputs.refuse(topic, "scan", f"dropped a scan: {exc}")
            return
        with self._lock:
            self._scan = (now, replace(scan, pose=world))  # the world model's frame
        if self._boxes is None:
            return
        # Boxes are ranged by the scan of their image's stamp (then placed in odometry's frame
        # and carried over); one stamped outside the window is still the robot's scan.
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        problem = self._boxes.on_scan(stamp, scan, self._ros_now())
        if problem is not None:
            self._inputs.refuse(topic, "stamp", f"a scan {problem}: not used to range boxes")

    def _on_battery(self, msg: BatteryState) -> None:
        percent = float(msg.percentage) * 100.0
        if math.isfinite(percent) and 0.0 <= percent <= 100.0:
            with self._lock:
                self._battery = (time.monotonic(), percent)

    def _on_image(self, msg: Image) -> None:
        try:
            frame = raw_image_frame(
                msg.data, msg.width, msg.height, msg.encoding, msg.step, source="go2"
            )
        except ValueError as exc:
            self._drop_frame(exc)
            return
        self._frame = frame

    def _on_compressed(self, msg: CompressedImage) -> None:
        try:
            self._frame = replace(to_camera_frame(bytes(msg.data)), source="go2")
        except ValueError as exc:
            self._drop_frame(exc)

    def _drop_frame(self, exc: ValueError) -> None:
        self._inputs.refuse(
            self.topic(self.config.camera_topic), "frame", f"dropped a camera frame: {exc}"
        )

    def _on_detections(self, msg: object) -> None:
        """On the detections' thread (ros_inputs): the newest message first."""
        with self._lock:
            self._detections_at = time.monotonic()
        state = self.last_state()
        with self._lock:
            frames = self._frames
            if self._map_odom is not None:
                m = self._map_odom
                frames = replace(frames, map=self.config.map_frame, odom_in_map=(m.x, m.y, m.yaw))
        reading = sightings_from_msg(
            msg, Pose2D(state.x, state.y, state.yaw), frames, self.now(), self._ros_now()
        )
        self._note_inputs(self.config.detections_topic, reading.notes)
        self._add_sightings(reading.seen, reading.problems)

    def _on_camera_info(self, msg: CameraInfo) -> None:
        assert self._boxes is not None  # subscribed only with the boxes' intake
        problem = self._boxes.on_camera_info(msg.k)
        if problem is not None:
            self.node.get_logger().warning(problem, throttle_duration_sec=30.0)

    def _on_boxes(self, msg: Any) -> None:
        """On the boxes' thread (ros_inputs): the newest message first."""
        assert self._boxes is not None  # subscribed only with the boxes' intake
        clock = self._ros_now()
        reading = self._boxes.read(msg, clock)
        self._note_inputs(self.config.coco_detections_topic, reading.notes)
        # Stamps are the image's (ROS clock); sightings are on the robot's clock, and in the
        # robot's world frame (the map, with SLAM, as it was when the image was taken).
        offset = self.now() - clock
        with self._lock:
            where = [self._to_world(o.x, o.y, 0.0, o.stamp) for o in reading.seen]
        seen = [
            replace(o, x=w.x, y=w.y, stamp=o.stamp + offset)
            for o, w in zip(reading.seen, where, strict=True)
        ]
        self._add_sightings(seen, reading.problems)
        with self._lock:  # after the sightings: look() waits for a report it can read
            self._detections_at = time.monotonic()
        for b in reading.bearings:
            self.node.get_logger().debug(
                f"{b.name}: bearing {math.degrees(b.direction):.0f} degrees only ({b.why})"
            )

    def _note_inputs(self, topic: str, notes: list[tuple[str, str]]) -> None:
        """What a message lost as a whole (a cap, stamps), into the input report."""
        for kind, text in notes:
            self._inputs.refuse(self.topic(topic), kind, text)

    @property
    def input_problems(self) -> str:
        """What the robot refused or cut of its inputs lately ('' when nothing), for the
        node's diagnostics (input_limits)."""
        return self._inputs.summary()

    def _ros_now(self) -> float:
        """This computer's ROS clock, which headers are stamped with (seconds)."""
        return float(self.node.get_clock().now().nanoseconds) * 1e-9

    def _add_sightings(self, seen: list[KnownObject], problems: list[str]) -> None:
        """New sightings into the board and the world model; what was refused, logged."""
        self._sightings.add(seen)
        with self._lock:
            belief = self._map
        if belief is not None:  # the world model plans with them too
            for o in seen:
                try:
                    belief.sight(o.name, o.x, o.y, o.stamp, o.confidence, o.radius)
                except ValueError as exc:  # checked already; a belief rule the board lacks
                    problems.append(str(exc))
        for problem in problems:
            self.node.get_logger().warning(
                f"dropped a detection: {problem}", throttle_duration_sec=5.0
            )

    def look(self) -> None:
        """Wait for the detector's next report (received after this call), at most
        `_LOOK_SECONDS`: it runs at its own rate, so what it said before the robot came to
        rest may be of another view. Nothing to wait for without a detections topic."""
        if not (self.config.detections_topic or self.config.coco_detections_topic):
            return
        since = time.monotonic()
        deadline = since + _LOOK_SECONDS
        while time.monotonic() < deadline:
            with self._lock:
                heard = self._detections_at
            if heard is not None and heard > since:
                return
            time.sleep(0.02)

    def in_view(self) -> tuple[Sighting, ...] | None:
        """What the detector reported in the last `IN_VIEW_SECONDS` (robot clock), as seen from
        where the robot is now, nearest first. None without a detections topic: nothing can
        be watched for by sight."""
        if not (self.config.detections_topic or self.config.coco_detections_topic):
            return None
        now, here = self.now(), self.last_state()
        seen = []
        for o in self._sightings.objects():
            if now - o.stamp > IN_VIEW_SECONDS:
                continue
            bearing = normalize_angle(math.atan2(o.y - here.y, o.x - here.x) - here.yaw)
            seen.append(
                Sighting(o.name, math.hypot(o.x - here.x, o.y - here.y), math.degrees(bearing))
            )
        # Boxes with no range (none in the scan, or too far): a direction in odometry's frame,
        # stamped with the image's time on the ROS clock.
        offset = now - self._ros_now()
        with self._lock:
            correction = self._map_odom.yaw if self._map_odom is not None else 0.0
        for b in self.bearings():
            if now - (b.stamp + offset) <= IN_VIEW_SECONDS:
                turn = normalize_angle(b.direction + correction - here.yaw)
                seen.append(Sighting(b.name, math.inf, math.degrees(turn)))
        return tuple(sorted(seen, key=lambda s: s.distance))

    def vocabulary(self) -> frozenset[str]:
        """The detector's classes (`detector_classes`) and every name it has reported: what
        a search may look for. Without a detector, nothing (no search can end)."""
        reported = (o.name for o in self.known_objects())
        coco = COCO_CLASSES if self.config.coco_detections_topic else ()
        return frozenset((*self.config.detector_classes, *coco, *reported))

    def bearings(self) -> tuple[Bearing, ...]:
        """The 2-D detector's boxes that had no usable range (BoxIntake keeps the latest)."""
        return self._boxes.bearings() if self._boxes is not None else ()

    def known_objects(self) -> tuple[KnownObject, ...]:
        """What the detections topic has reported and what the world model holds (sightings
        the agent made), one per name (the latest), in the world frame (`world_frame`)."""
        with self._lock:
            belief = self._map
        return merge_sightings(
            belief.objects if belief is not None else (), self._sightings.objects()
        )

    def _keep_alive(self) -> None:
        with self._lock:
            idle = not any(self._command)
        if idle:
            return
        topic = self._discover_velocity_topic()
        with self._send_lock:
            with self._lock:
                command, due = self._command, time.monotonic() - self._last_sent >= 0.08
                estopped = self._body.estopped
            if any(command) and due and not estopped:
                self._publish_twist(command, topic)

    def _warn_without_odometry(self) -> None:
        if self._pose_at is None:
            self.node.get_logger().warning(
                f"no odometry on {self.topic(self.config.odom_topic)} yet: is go2_ros2_sdk (or "
                "`shadowhound sim-driver`) running, with the same ROS_DOMAIN_ID and RMW? "
                "`shadowhound doctor --go2` checks the link",
                throttle_duration_sec=30.0,
            )

    # -- Robot protocol ------------------------------------------------------------------

    def _locate(self, now: float) -> tuple[Pose2D, int, tuple[float, float, float]]:
        """The pose now in the world frame (the map once SLAM's map -> odom is known), and the
        map -> odom jumps seen. With self._lock held."""
        return self._to_world(*self._tracker.pose(now)), self._relocalized, self._jumps

    def _pose_problem(self) -> str:
        topic = self.topic(self.config.odom_topic)
        if self._pose_at is None:
            waited = time.monotonic() - self._started
            return (
                f"no odometry received on {topic} in {waited:.1f} s: is go2_ros2_sdk "
                "running, with the same ROS_DOMAIN_ID and RMW?"
            )
        age = time.monotonic() - self._pose_at
        return (
            f"no odometry on {topic} for {age:.1f} s: is go2_ros2_sdk running and the "
            "robot connected (WebRTC allows one client: close the phone app)?"
        )

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Body-frame velocity; all zero is a stop (StopMove), since the driver drops zero
        Twists."""
        values = finite_velocity(vx, vy, wz)
        if not any(values):
            self._halt()
            return
        c = self.config
        vx, vy, wz = capped(values, c.max_linear_speed, c.max_angular_speed)
        # As the driver will send it (2 decimals), so the tracker models what the robot does;
        # the last millimetres of an approach would otherwise round to standing still.
        command = (go2_api.movable(vx), go2_api.movable(vy), go2_api.movable(wz))
        if not self.last_state().connected:
            raise RobotError(self._pose_problem() + " Not moving without odometry.")
        with self._lock:
            starting, estopped = self._halted, self._body.estopped
        if starting:
            self._check_publishers()  # two odometry sources: found before the first step
            if self.joints_held and not estopped:
                # Standing with its joints held (a StandUp from elsewhere): every Move would be
                # ignored. BalanceStand first; the walk starts once the robot walks.
                self.set_posture(Posture.STANDING)
        with self._lock:
            untrusted = self._intake.problem(time.monotonic())
        if untrusted:
            raise RobotError(f"odometry is not trusted: {untrusted}. Not moving.")
        lag = self.odom_latency
        if starting and lag >= MAX_LATENCY - 0.05:  # measured at the bound: maybe more
            raise RobotError(
                f"odometry lags the robot by {lag:.1f} s or more (measured): too late to steer "
                f"on (ShadowHound steers on odometry up to {MAX_LATENCY:g} s late; check the "
                "link: docs/go2.md). Not moving."
            )
        topic = self._discover_velocity_topic()
        self._command_velocity(command, lambda sent: self._publish_twist(sent, topic))

    def stop(self) -> None:
        """Nav2's goals cancelled, and StopMove now (thread-safe); the keep-alive goes quiet."""
        now = time.monotonic()
        if self._navigator is not None:  # else Nav2's controller drives on
            self._navigator.cancel_all()
        self._stop_move(now)

    def watch_estop(self, listener: Callable[[bool], None]) -> None:
        """Call `listener(True)` after an e-stop on `estop_topic` stopped the robot, and
        `listener(False)` when a person releases it on `estop_release_topic`."""
        self._estop_listeners.append(listener)

    def _estop_pressed(self) -> None:
        """On the e-stop listener's own thread: the hard stop first, then whoever watches."""
        self.emergency_stop()
        self.node.get_logger().warning(
            f"E-STOP on {self.config.estop_topic}: the robot is stopped and latched"
        )
        for listener in list(self._estop_listeners):
            listener(True)

    def _estop_released(self) -> None:
        self.release_estop()
        for listener in list(self._estop_listeners):
            listener(False)

    def set_posture(self, posture: Posture) -> None:
        """Go to `posture` through standing, one sport command at a time, each done when
        go2_states shows the posture it leads to. Nothing is sent when already there."""
        self._body.set_posture(posture, self._stand_before_balancing)

    def _stand_before_balancing(self, what: str) -> None:
        """After StandUp (or RiseSit): BalanceStand went once go2_states showed the body
        standing, whatever the mode (firmware differ: JointLock 6, Damping 7), or after a
        bounded wait; this says when the wait ran out."""
        self.node.get_logger().warning(
            f"{what} sent, but {self._postures.topic} shows {self._postures.describe()} "
            f"after {STAND_UP_BOUND:g} s; sending BalanceStand anyway (the robot queues "
            "posture commands)"
        )

    def perform(self, trick: str) -> None:
        info = trick_info(trick)
        ai_mode = info.api_id in go2_api.AI_MODE_TRICKS
        if ai_mode and not self.config.firmware_tricks:
            raise RobotError(
                f"{trick} (api id {info.api_id}) runs only on Go2 firmware that has it, in the "
                "'ai' motion mode; it is off unless enabled (ROS parameter "
                "go2_firmware_tricks, see docs/go2.md)"
            )

        def ai() -> None:  # recent firmware runs these only in the "ai" motion mode
            self._request(go2_api.MOTION_SWITCH, {"name": "ai"}, go2_api.MOTION_SWITCHER_TOPIC)

        self._body.perform(trick, ai if ai_mode else None)

    def get_camera_frame(self) -> CameraFrame | None:
        return self._frame

    def get_scan(self) -> Scan | None:
        """The latest scan from `scan`, or None when none arrived within `scan_timeout`."""
        with self._lock:
            latest = self._scan
        if latest is None or time.monotonic() - latest[0] > self.config.scan_timeout:
            return None
        return latest[1]

    def belief(self) -> Belief | None:
        """The world model: the latest map from `map` (a mission may update it from scans
        until the next map arrives) and the objects known (detections, sightings), or None
        before a map arrives (then paths are straight lines)."""
        with self._lock:
            return self._map

    def navigator(self) -> Nav2Navigator | None:
        """Nav2's NavigateToPose client (goals in the world frame: SLAM's map when there is
        one, else odometry's), or None when the `nav2_action` is ''. Whether a server answers
        is its `ready()`."""
        if self._navigator is not None:
            self._navigator.frame = self.world_frame
        return self._navigator

    def _closing(self) -> None:
        """The reading threads and the e-stop listener end (close(), before the executor's
        end)."""
        self._inputs.close()
        if self._estop_node is not None:
            self._estop_node.close()

    def _destroy_node(self) -> None:
        if self._navigator is not None:
            self._navigator.destroy()
        super()._destroy_node()

    # -- topics out ----------------------------------------------------------------------

    def _discover_velocity_topic(self) -> str:
        """The configured topic, or the one the graph needs now (see go2_topics). The graph is
        read at every command (cheap: a local cache), so when a relay or a listener comes or
        goes, or its node's name becomes known, the next command follows."""
        if self.config.cmd_vel_topic:
            return self.config.cmd_vel_topic

        def endpoints(infos: Callable[[str], list[Any]]) -> dict[str, list[tuple[str, str]]]:
            return {
                name: [
                    (node_name(i.node_namespace, i.node_name), i.topic_type)
                    for i in infos(self.topic(name))
                ]
                for name in VELOCITY_TOPICS
            }

        with self._lock:
            route = self._route
        try:
            found = choose_velocity_topic(
                endpoints(self.node.get_subscriptions_info_by_topic),
                endpoints(self.node.get_publishers_info_by_topic),
                names={name: self.topic(name) for name in VELOCITY_TOPICS},
            )
        except Exception:  # rclpy raises several types once the context is shutting down
            return route.topic if route is not None else VELOCITY_TOPICS[-1]
        if route is None or found.topic != route.topic:
            self.node.get_logger().info(
                f"velocity commands go to {self.topic(found.topic)} ({found.why})"
            )
        with self._lock:
            self._route = found
        return found.topic

    @property
    def velocity_route(self) -> VelocityRoute:
        """Where velocity goes and why, in full topic names (for diagnostics and logs)."""
        topic = self._discover_velocity_topic()
        with self._lock:
            route = self._route
        if self.config.cmd_vel_topic or route is None:
            return VelocityRoute(self.topic(topic), "configured (cmd_vel_topic)")
        return replace(route, topic=self.topic(route.topic))

    def _publish_twist(self, command: tuple[float, float, float], topic: str) -> None:
        """Publish one Twist; the caller holds the send lock."""
        msg = Twist()
        msg.linear.x, msg.linear.y, msg.angular.z = command
        with self._lock:
            self._last_sent = time.monotonic()
        if self._context.ok():
            self._twist_pubs[topic].publish(msg)

    def _request(
        self,
        api_id: int,
        parameter: dict[str, object] | None = None,
        topic: str = go2_api.SPORT_TOPIC,
    ) -> None:
        if self._context.ok():
            self._request_pub.publish(
                WebRtcReq(
                    id=0,
                    topic=topic,
                    api_id=api_id,
                    parameter=json.dumps(parameter) if parameter else "",
                    priority=0,
                )
            )

    def say(self, text: str) -> None:
        """Publish `text` once on `speech_topic` (a publish queues the message and returns)."""
        if self._speech_pub is None:
            raise RobotError("this Go2 has no voice: speech_topic is '' (set it, e.g. /tts)")
        if self._context.ok():
            self._speech_pub.publish(String(data=text))
