"""`shadowhound sim-driver`'s settings: one table, read from command-line options and ROS
parameters alike (defaults < `--ros-args -p name:=value` < `--option value`).

Pure Python (no rclpy), so the checks and the help text are testable on their own.
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from typing import Any

from ..errors import ParameterError

INTERFACES = ("go2_ros2_sdk", "unitree_ros2")
# What a robot on unitree_ros2 does not have: go2_ros2_sdk's relay, sensors and Nav2 are off.
_UNITREE_OFF = {
    "relay": False,
    "camera_rate_hz": 0.0,
    "scan_rate_hz": 0.0,
    "map": False,
    "navigate_to_pose": False,
    "detector": "none",
}
DETECTIONS_RATE_HZ = 2.0  # the simulated detector's rate: modest, as a camera detector runs
_TOPIC = re.compile(r"^[~/]?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$")


@dataclass(frozen=True)
class DriverSettings:
    """Checked settings of the simulated driver."""

    robots: int = 1
    interface: str = "go2_ros2_sdk"
    start_posture: str = "standing"
    stand_up_mode: int = 6
    relay: bool = True
    relay_timeout: float = 0.5
    move_timeout: float = 1.0
    odom_rate_hz: float = 20.0
    odom_delay: float = 0.2
    odom_burst: int = 1
    state_rate_hz: float = 10.0
    posture_seconds: float = 1.5
    battery: float | None = None
    battery_topic: str = "battery_state"
    battery_drain: float = 0.01
    truth_rate_hz: float = 50.0
    camera_rate_hz: float = 5.0
    camera_width: int = 160
    camera_height: int = 120
    scan_rate_hz: float = 10.0
    map: bool = True
    navigate_to_pose: bool = True
    nav_speed: float = 0.4
    detector: str = "shadowhound"
    slam: bool = False
    odom_drift: float = 0.0


@dataclass(frozen=True)
class Option:
    """One setting: its type, allowed range (numbers), metavar and help."""

    kind: type
    help: str
    low: float = -math.inf
    high: float = math.inf
    metavar: str = ""
    choices: tuple[str, ...] = ()  # for a str that is not a topic name


OPTIONS: dict[str, Option] = {
    "robots": Option(
        int,
        "robots to simulate; 2 or more name every topic robot{i}/..., as "
        "go2_ros2_sdk does with several ROBOT_IPs",
        1,
        8,
        "N",
    ),
    "interface": Option(
        str,
        "the robot's ROS 2 interface: go2_ros2_sdk (cmd_vel_out, webrtc_req, odom, go2_states "
        "and the rest) or unitree_ros2 (a Go2 EDU through Unitree's own: unitree_api/Request on "
        "api/sport/request, unitree_go/SportModeState on lf/sportmodestate, unitree_go/LowState "
        "on lf/lowstate; nothing of go2_ros2_sdk's: no relay, camera, scan, map, detector, "
        "navigate_to_pose)",
        metavar="INTERFACE",
        choices=INTERFACES,
    ),
    "start_posture": Option(
        str,
        "posture the robots start in (lying: mode LieDown, sitting: Sit, standing: BalanceStand)",
        metavar="POSTURE",
        choices=("standing", "sitting", "lying"),
    ),
    "stand_up_mode": Option(
        int,
        "go2_states mode during and after StandUp: 6 JointLock, 7 Damping (as some firmware "
        "reports) or 0 Idle: Moves ignored until BalanceStand; 1 BalanceStand: StandUp ends "
        "balanced and walks",
        0,
        7,
        "MODE",
    ),
    "relay": Option(
        bool,
        "a twist_mux-like relay (node 'twist_mux', not namespaced) from "
        "cmd_vel (priority 5) and cmd_vel_joy (10) to cmd_vel_out, as "
        "go2_ros2_sdk's launch starts with teleop; --no-relay: the driver "
        "hears cmd_vel_out only",
    ),
    "relay_timeout": Option(
        float,
        "seconds a relay input stays active after its last message (twist_mux's timeout)",
        0.05,
        5,
        "SECONDS",
    ),
    "move_timeout": Option(
        float,
        "seconds the robot keeps executing a Move that is not renewed (firmware behaviour)",
        0.1,
        5,
        "SECONDS",
    ),
    "odom_rate_hz": Option(float, "odom publishing rate", 1, 200, "HZ"),
    "odom_delay": Option(
        float,
        "seconds odom lags the truth: each odom carries the true "
        "pose of this long ago (stamped when published)",
        0,
        5,
        "SECONDS",
    ),
    "odom_burst": Option(
        int,
        "odometry samples that travel together, as on a busy Wi-Fi link (go2_ros2_sdk #231): "
        "held back until the last of N is due, then published back to back",
        1,
        10,
        "N",
    ),
    "state_rate_hz": Option(
        float, "go2_states publishing rate (delayed by --odom-delay, like odometry)", 1, 100, "HZ"
    ),
    "posture_seconds": Option(
        float,
        "seconds a posture change (StandUp, StandDown, Sit, "
        "RiseSit) takes; BalanceStand and Damp take 0.3 of it, "
        "RecoveryStand 1.3",
        0,
        10,
        "SECONDS",
    ),
    "battery": Option(
        float,
        "publish sensor_msgs/BatteryState starting at this charge (go2_ros2_sdk publishes none)",
        0,
        100,
        "PERCENT",
    ),
    "battery_topic": Option(
        str, "topic of the battery state (relative, per robot)", metavar="TOPIC"
    ),
    "battery_drain": Option(float, "percent of charge used per second while on", 0, 10, "PERCENT"),
    "truth_rate_hz": Option(float, "rate of the ground truth on sim_driver/truth", 1, 200, "HZ"),
    "camera_rate_hz": Option(float, "camera/image_raw rate (0 = no camera)", 0, 30, "HZ"),
    "camera_width": Option(int, "camera image width in pixels", 16, 640, "PIXELS"),
    "camera_height": Option(int, "camera image height in pixels", 12, 480, "PIXELS"),
    "scan_rate_hz": Option(
        float,
        "scan (sensor_msgs/LaserScan, 360 beams, 0.1-8 m, from the "
        "simulator's ray casting) rate (0 = no scan)",
        0,
        50,
        "HZ",
    ),
    "map": Option(
        bool,
        "publish the scene's nav_msgs/OccupancyGrid on map (5 cm cells, frame "
        "odom, transient local as map_server does)",
    ),
    "navigate_to_pose": Option(
        bool,
        "serve Nav2's NavigateToPose action on navigate_to_pose "
        "with the project's planner and path follower; "
        "--no-navigate-to-pose: as a Go2 without Nav2",
    ),
    "nav_speed": Option(float, "m/s the navigate_to_pose server walks at", 0.05, 1.0, "M/S"),
    "detector": Option(
        str,
        f"act as a detector at {DETECTIONS_RATE_HZ:g} Hz, reporting the objects the simulated "
        "camera sees (field of view, occlusion). shadowhound: "
        "shadowhound_interfaces/DetectionArray on detections, true centres in odom, "
        "confidence 1, true radius; coco: vision_msgs/Detection2DArray on detected_objects "
        "as go2_ros2_sdk's coco_detector, each object's box in the camera image under its "
        "COCO name, with camera/camera_info; none: no detector",
        metavar="KIND",
        choices=("shadowhound", "coco", "none"),
    ),
    "slam": Option(
        bool,
        "act as slam_toolbox too: publish map -> odom on /tf, the correction that makes "
        "odometry (drifting with --odom-drift) agree with the truth, and the map in frame map "
        "(one robot only)",
    ),
    "odom_drift": Option(
        float,
        "odometry's drift: every metre walked and radian turned shows as 1 + this (0.05: 5 "
        "percent of distance and heading), so odom wanders from the truth as a real Go2's "
        "does; --slam corrects it on /tf",
        0,
        0.5,
        "FRACTION",
    ),
}
DEFAULTS = DriverSettings()
_WANTED = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}


def parse_settings(values: Mapping[str, Any]) -> DriverSettings:
    """Check raw values (missing ones take their defaults); raises ParameterError listing
    every problem at once, each with what is allowed."""
    unknown = sorted(set(values) - set(OPTIONS))
    problems = (
        [f"unknown setting(s) {', '.join(unknown)}; known: {', '.join(OPTIONS)}"] if unknown else []
    )
    out: dict[str, Any] = {}
    for f in fields(DriverSettings):
        option, value = OPTIONS[f.name], values.get(f.name, getattr(DEFAULTS, f.name))
        if value is None and getattr(DEFAULTS, f.name) is None:
            out[f.name] = None
            continue
        if option.kind is bool:
            ok = isinstance(value, bool)
        elif option.kind is int:
            ok = isinstance(value, int) and not isinstance(value, bool)
        elif option.kind is float:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        else:
            ok = isinstance(value, str)
        if not ok:
            problems.append(
                f"{f.name} must be {_WANTED[option.kind]}, got {type(value).__name__} {value!r}"
            )
        elif option.kind in (int, float) and not (
            math.isfinite(value) and option.low <= value <= option.high
        ):
            problems.append(f"{f.name} must be in {option.low:g}..{option.high:g}, got {value}")
        elif option.choices and value not in option.choices:
            problems.append(f"{f.name} must be one of {', '.join(option.choices)}, got {value!r}")
        elif option.kind is str and not option.choices and not _TOPIC.match(value):
            problems.append(f"{f.name} {value!r} is not a valid ROS topic name")
        else:
            out[f.name] = option.kind(value)
    if out.get("slam") and out.get("robots", 1) > 1:
        problems.append(
            "slam is for one robot: with several, each would publish map -> odom for the same "
            "frames (use --robots 1)"
        )
    if out.get("interface") == "unitree_ros2":
        if out.get("slam"):
            problems.append("slam is go2_ros2_sdk's side: not with interface unitree_ros2")
        out.update(_UNITREE_OFF)
    if problems:
        raise ParameterError("invalid settings: " + "; ".join(problems))
    return DriverSettings(**out)


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def build_parser(prog: str, description: str, epilog: str) -> argparse.ArgumentParser:
    """The command line: one option per setting (argument_default SUPPRESS, so only options
    given on the command line override the ROS parameters)."""
    parser = argparse.ArgumentParser(
        prog=prog,
        description=description,
        epilog=epilog,
        argument_default=argparse.SUPPRESS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    for name, option in OPTIONS.items():
        default = getattr(DEFAULTS, name)
        if option.kind is bool:
            parser.add_argument(
                _flag(name),
                dest=name,
                action=argparse.BooleanOptionalAction,
                help=f"{option.help} (default: {'on' if default else 'off'})",
            )
            continue
        shown = (
            "none" if default is None else f"{default:g}" if isinstance(default, float) else default
        )
        parser.add_argument(
            _flag(name),
            dest=name,
            type=option.kind,
            metavar=option.metavar,
            choices=option.choices or None,
            help=f"{option.help} (default: {shown})",
        )
    return parser


def split_argv(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """(the driver's own options, the ROS arguments from --ros-args on)."""
    args = list(argv)
    if "--ros-args" in args:
        at = args.index("--ros-args")
        return args[:at], args[at:]
    return args, []
