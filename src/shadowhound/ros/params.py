"""The node's ROS parameters: names, defaults, and checking them into typed settings.

Pure Python (no rclpy): the node reads raw parameter values and hands them to
`parse_parameters`, which reports every problem at once with what is allowed.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, get_args

from ..config import ShadowHoundConfig, load_config
from ..errors import ParameterError
from ..robot.go2.motion import MAX_LATENCY
from ..robot_config import ROBOT_NAME, ROBOT_NAME_RULE

NODE_NAME = "shadowhound_mission_agent"

# Name -> (default, help). The default also fixes the expected type.
PARAMETERS: dict[str, tuple[Any, str]] = {
    "backend_config": (
        "offline",
        "config profile name (offline, openai, ollama, vllm, llamacpp) or a path to a YAML file",
    ),
    "robot": (
        "sim",
        "sim (simulated Go2 in this process), go2 (a Go2 through go2_ros2_sdk's "
        "topics, or `shadowhound sim-driver`) or go2_edu (a Go2 EDU through Unitree's "
        "unitree_ros2, or `shadowhound sim-driver --interface unitree_ros2`)",
    ),
    "time_scale": (
        1.0,
        "simulated robot: real seconds per simulated second (1 = real time, "
        "0 = as fast as possible)",
    ),
    "camera_topic": ("/camera/image_raw", "camera images the agent looks at"),
    "camera_type": (
        "auto",
        "raw (sensor_msgs/Image), compressed (sensor_msgs/CompressedImage) "
        "or auto (compressed when the topic name ends in 'compressed')",
    ),
    "mission_topic": ("mission_command", "std_msgs/String missions to run"),
    "status_topic": ("mission_status", "std_msgs/String EXECUTING/COMPLETED/FAILED reports"),
    "robot_status_topic": ("/shadowhound/robot_status", "std_msgs/String JSON robot state, 5 Hz"),
    "diagnostics_topic": ("/shadowhound/diagnostics", "diagnostic_msgs/DiagnosticArray, 1 Hz"),
    "web_interface_port": (8080, "port of the web dashboard (1..65535)"),
    "enable_web_ui": (False, "serve the web dashboard on 127.0.0.1:web_interface_port"),
    "robot_namespace": (
        "",
        "go2: go2_ros2_sdk's robot namespace, e.g. robot0 ('' = none); "
        "the Go2 topics below are relative to it",
    ),
    "robot_name": (
        "",
        "which robot this is to memory: only its own places and sightings are goals "
        "(robot.name; '' = the profile's, else the type and namespace: sim, go2, go2:robot0)",
    ),
    "cmd_vel_topic": (
        "",
        "go2: geometry_msgs/Twist velocity out; '' = discovered: cmd_vel when "
        "something (twist_mux) subscribes it, else the driver's cmd_vel_out",
    ),
    "webrtc_topic": ("webrtc_req", "go2: go2_interfaces/WebRtcReq sport commands out"),
    "odom_topic": ("odom", "go2: nav_msgs/Odometry in"),
    "go2_states_topic": ("go2_states", "go2: go2_interfaces/Go2State in"),
    "odom_timeout": (0.5, "go2: seconds without odometry before a moving robot stops (0.05..10)"),
    "odom_latency": (
        -1.0,
        "go2: seconds odometry lags the robot (0..5); -1 = measured at each start from rest",
    ),
    "battery_topic": (
        "",
        "go2: sensor_msgs/BatteryState in ('' = none: the battery level is "
        "reported unknown; go2_ros2_sdk publishes none)",
    ),
    "detections_topic": (
        "",
        "go2: shadowhound_interfaces/DetectionArray in, from any detector "
        "('' = none); each detection becomes a known object",
    ),
    "detector_classes": (
        "",
        "go2: the names the detector can report, comma-separated ('red ball, chair'): "
        "a search may look for these and for names it has reported; '' = only those",
    ),
    "coco_detections_topic": (
        "",
        "go2: vision_msgs/Detection2DArray in from a 2-D detector (go2_ros2_sdk's "
        "coco_detector: detected_objects; '' = none); each box is placed with camera_info, "
        "odometry and the scan",
    ),
    "camera_info_topic": (
        "camera/camera_info",
        "go2: sensor_msgs/CameraInfo in (best effort), the camera model for the boxes",
    ),
    "camera_x": (0.3, "go2: metres the camera sits ahead of base_link (-2..2)"),
    "camera_y": (0.0, "go2: metres the camera sits left of base_link (-2..2)"),
    "camera_yaw": (0.0, "go2: radians the camera looks left of the heading (-pi..pi)"),
    "coco_max_range": (
        6.0,
        "go2: metres (0.5..30) beyond which a box is a bearing only, never a place to go",
    ),
    "navigation": (
        "",
        "nav.goto: auto (Nav2's navigate_to_pose when it answers, else the "
        "project's own planner), nav2 (Nav2 required), direct (never Nav2); "
        "'' = the profile's (auto unless it says otherwise)",
    ),
    "map_topic": (
        "map",
        "go2: nav_msgs/OccupancyGrid map in (transient local, as map_server "
        "and slam_toolbox publish it); '' = no map: paths are straight lines",
    ),
    "scan_topic": ("scan", "go2: sensor_msgs/LaserScan in ('' = none)"),
    "nav2_action": ("navigate_to_pose", "go2: Nav2's NavigateToPose action ('' = no Nav2)"),
    "speech_topic": (
        "/tts",
        "go2: std_msgs/String words to say out (go2_ros2_sdk's tts_node listens on "
        "/tts); '' = none: the robot does not speak aloud",
    ),
    "map_frame": (
        "map",
        "go2: SLAM's map frame: with its map -> odom on /tf (slam_toolbox), poses, places, "
        "objects, the map and Nav2 goals are in it and SLAM's corrections are followed; '' = "
        "read no TF (the world is odometry's frame)",
    ),
    "go2_firmware_tricks": (
        False,
        "go2: allow the tricks that need firmware support and the "
        "'ai' motion mode (flips, handstand, 1301-1305)",
    ),
}

CAMERA_TYPES = ("auto", "raw", "compressed")
# '' = discovered / none
_OPTIONAL_TOPICS = (
    "cmd_vel_topic",
    "battery_topic",
    "detections_topic",
    "coco_detections_topic",
    "map_topic",
    "scan_topic",
    "nav2_action",
    "speech_topic",
)
NAVIGATION: tuple[str, ...] = get_args(ShadowHoundConfig.model_fields["navigation"].annotation)
ROBOTS = ("sim", "go2", "go2_edu")
_FRAME = re.compile(r"^/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")
_TOPIC = re.compile(r"^[~/]?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")


@dataclass(frozen=True)
class NodeSettings:
    """Checked parameter values."""

    backend_config: str = "offline"
    robot: str = "sim"
    time_scale: float = 1.0
    camera_topic: str = "/camera/image_raw"
    camera_type: str = "auto"
    mission_topic: str = "mission_command"
    status_topic: str = "mission_status"
    robot_status_topic: str = "/shadowhound/robot_status"
    diagnostics_topic: str = "/shadowhound/diagnostics"
    web_interface_port: int = 8080
    enable_web_ui: bool = False
    robot_namespace: str = ""
    robot_name: str = ""
    cmd_vel_topic: str = ""
    webrtc_topic: str = "webrtc_req"
    odom_topic: str = "odom"
    go2_states_topic: str = "go2_states"
    odom_timeout: float = 0.5
    odom_latency: float = -1.0
    battery_topic: str = ""
    detections_topic: str = ""
    detector_classes: str = ""
    coco_detections_topic: str = ""
    camera_info_topic: str = "camera/camera_info"
    camera_x: float = 0.3
    camera_y: float = 0.0
    camera_yaw: float = 0.0
    coco_max_range: float = 6.0
    go2_firmware_tricks: bool = False
    navigation: str = ""
    map_topic: str = "map"
    scan_topic: str = "scan"
    nav2_action: str = "navigate_to_pose"
    speech_topic: str = "/tts"
    map_frame: str = "map"

    @property
    def camera_compressed(self) -> bool:
        if self.camera_type == "auto":
            return self.camera_topic.rstrip("/").endswith("compressed")
        return self.camera_type == "compressed"

    def agent_settings(self) -> ShadowHoundConfig:
        """The agent's configuration: the profile, then these parameters on top. For go2 the
        parameters fill the profile's `robot` settings (a parameter left at its default keeps
        the profile's value); the Go2's motion settings come with `robot: go2` (config)."""
        overrides: dict[str, Any] = {"sim": {"time_scale": self.time_scale}}
        if self.navigation:
            overrides["navigation"] = self.navigation
        # Merged into the profile's robot settings when it names the same backend, else they
        # replace them whole (load_config); a parameter left at its default keeps the profile's.
        named = {"name": self.robot_name} if self.robot_name else {}
        if self.robot == "go2":
            defaults = NodeSettings().go2_options()
            given = {k: v for k, v in self.go2_options().items() if v != defaults[k]}
            overrides["robot"] = {**given, **named, "type": "go2"}
        elif self.robot == "go2_edu":  # the namespace is the one parameter it shares
            namespace = {"namespace": self.robot_namespace} if self.robot_namespace else {}
            overrides["robot"] = {**namespace, **named, "type": "go2_edu"}
        else:
            overrides["robot"] = {**named, "type": self.robot}
        return load_config(self.backend_config, overrides)

    def go2_options(self) -> dict[str, Any]:
        """The Go2's settings these parameters give, as the profile's `robot:` section takes
        them (robot_config.Go2RobotSettings's fields)."""
        return {
            "namespace": self.robot_namespace,
            "cmd_vel_topic": self.cmd_vel_topic,
            "webrtc_topic": self.webrtc_topic,
            "odom_topic": self.odom_topic,
            "state_topic": self.go2_states_topic,
            "odom_timeout": self.odom_timeout,
            "odom_latency": None if self.odom_latency < 0 else self.odom_latency,
            "battery_topic": self.battery_topic,
            "detections_topic": self.detections_topic,
            "detector_classes": tuple(
                n for n in (c.strip() for c in self.detector_classes.split(",")) if n
            ),
            "coco_detections_topic": self.coco_detections_topic,
            "camera_info_topic": self.camera_info_topic,
            "camera_x": self.camera_x,
            "camera_y": self.camera_y,
            "camera_yaw": self.camera_yaw,
            "coco_max_range": self.coco_max_range,
            "firmware_tricks": self.go2_firmware_tricks,
            "map_topic": self.map_topic,
            "scan_topic": self.scan_topic,
            "nav2_action": self.nav2_action,
            "speech_topic": self.speech_topic,
            "map_frame": self.map_frame,
        }


_WANTED = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}


def _kind(value: Any) -> str:
    return "bool" if isinstance(value, bool) else type(value).__name__


def parse_parameters(values: Mapping[str, Any]) -> NodeSettings:
    """Check raw parameter values (missing ones take their defaults). Raises ParameterError."""
    problems: list[str] = []
    out: dict[str, Any] = {}
    for f in fields(NodeSettings):
        default, _help = PARAMETERS[f.name]
        value = values.get(f.name, default)
        if isinstance(default, bool):
            ok = isinstance(value, bool)
        elif isinstance(default, int):
            ok = isinstance(value, int) and not isinstance(value, bool)
        elif isinstance(default, float):
            ok = isinstance(value, (int, float)) and not isinstance(value, bool)
            value = float(value) if ok else value
        else:
            ok = isinstance(value, str)
        if not ok:
            problems.append(
                f"{f.name} must be {_WANTED[type(default)]}, got {_kind(value)} {value!r}"
            )
            continue
        out[f.name] = value
    unknown_topics = [
        n
        for n in (
            "camera_topic",
            "mission_topic",
            "status_topic",
            "robot_status_topic",
            "diagnostics_topic",
            "cmd_vel_topic",
            "webrtc_topic",
            "odom_topic",
            "go2_states_topic",
            "battery_topic",
            "detections_topic",
            "coco_detections_topic",
            "camera_info_topic",
            "map_topic",
            "scan_topic",
            "nav2_action",
            "speech_topic",
        )
        if n in out and not _TOPIC.match(out[n]) and (out[n] or n not in _OPTIONAL_TOPICS)
    ]
    frame = out.get("map_frame", "")
    if frame and not _FRAME.match(frame):
        problems.append(
            f"map_frame {frame!r} is not a frame id (letters, digits, '_' and '/' separators, "
            "not starting with a digit); '' reads no TF"
        )
    problems += [
        f"{n} {out[n]!r} is not a valid ROS topic name (letters, digits, '_' and "
        "'/' separators, not starting with a digit)"
        for n in unknown_topics
    ]
    if "camera_type" in out and out["camera_type"] not in CAMERA_TYPES:
        problems.append(
            f"camera_type must be one of {', '.join(CAMERA_TYPES)}, got {out['camera_type']!r}"
        )
    if out.get("navigation") and out["navigation"] not in NAVIGATION:
        problems.append(
            f"navigation must be one of {', '.join(NAVIGATION)} (or '' for the "
            f"profile's), got {out['navigation']!r}"
        )
    if "robot" in out and out["robot"] not in ROBOTS:
        problems.append(
            f"robot must be sim or go2, got {out['robot']!r} (or go2_edu: a Go2 EDU through "
            "unitree_ros2)"
        )
    namespace = out.get("robot_namespace", "")
    if namespace.strip("/") and not _TOPIC.match(namespace.strip("/")):
        problems.append(f"robot_namespace {namespace!r} is not a valid ROS namespace (e.g. robot0)")
    name = out.get("robot_name", "")
    if name and not ROBOT_NAME.match(name):
        problems.append(
            f"robot_name {name!r} is not a robot's name: {ROBOT_NAME_RULE}; '' = the "
            "profile's, else the type and namespace"
        )
    for name, low, high in (
        ("camera_x", -2.0, 2.0),
        ("camera_y", -2.0, 2.0),
        ("camera_yaw", -math.pi, math.pi),
        ("coco_max_range", 0.5, 30.0),
    ):
        value = out.get(name)
        if value is not None and not (math.isfinite(value) and low <= value <= high):
            problems.append(f"{name} must be a number in {low:g}..{high:g}, got {value}")
    timeout = out.get("odom_timeout")
    if timeout is not None and not (math.isfinite(timeout) and 0.05 <= timeout <= 10):
        problems.append(f"odom_timeout must be a number of seconds in 0.05..10, got {timeout}")
    latency = out.get("odom_latency")
    if latency is not None and not (latency == -1.0 or 0 <= latency <= MAX_LATENCY):
        problems.append(
            f"odom_latency must be -1 (measured) or seconds in 0..{MAX_LATENCY:g}, got {latency}"
        )
    port = out.get("web_interface_port")
    if port is not None and not 1 <= port <= 65535:
        problems.append(f"web_interface_port must be in 1..65535, got {port}")
    scale = out.get("time_scale")
    if scale is not None and not (math.isfinite(scale) and 0 <= scale <= 100):
        problems.append(
            f"time_scale must be a number in 0..100 (1 = real time, 0 = as fast as "
            f"possible), got {scale}"
        )
    if "backend_config" in out and not out["backend_config"].strip():
        problems.append("backend_config must name a profile or a YAML file, got ''")
    if problems:
        raise ParameterError("invalid ROS parameters: " + "; ".join(problems))
    return NodeSettings(**out)


def describe_parameters() -> str:
    """Help text: every parameter with its default."""
    lines = [
        f"  {name} (default {default!r}): {text}" for name, (default, text) in PARAMETERS.items()
    ]
    return "\n".join(lines)
