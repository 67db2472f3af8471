"""What the robot is and where it is: postures, poses, camera frames and the state snapshot."""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from enum import Enum
from typing import Any

from .jsonout import number


class Posture(str, Enum):
    """Body posture of a quadruped. Motion is only possible while standing."""

    STANDING = "standing"
    SITTING = "sitting"
    LYING = "lying"


def normalize_angle(angle: float) -> float:
    """Wrap an angle in radians to (-pi, pi] (REP-103)."""
    wrapped = math.remainder(angle, 2.0 * math.pi)
    return math.pi if wrapped == -math.pi else wrapped


def compose(
    a: tuple[float, float, float], d: tuple[float, float, float]
) -> tuple[float, float, float]:
    """Pose `a` moved by `d` (given in a's frame): as transforms (x, y, yaw), a after d."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return a[0] + d[0] * c - d[1] * s, a[1] + d[0] * s + d[1] * c, normalize_angle(a[2] + d[2])


def inverse(p: tuple[float, float, float]) -> tuple[float, float, float]:
    """The rigid motion that undoes `p` (x, y, yaw): compose(p, inverse(p)) is no motion."""
    c, s = math.cos(p[2]), math.sin(p[2])
    return -c * p[0] - s * p[1], s * p[0] - c * p[1], normalize_angle(-p[2])


@dataclass(frozen=True)
class Pose2D:
    """A planar pose in the odom frame: metres and radians, yaw counter-clockwise positive."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def distance_to(self, x: float, y: float) -> float:
        return math.hypot(x - self.x, y - self.y)

    def unknown(self) -> str:
        """What of the pose is not a finite number ("x=nan"), or "" when all of it is."""
        return not_finite(x=self.x, y=self.y, yaw=self.yaw)


def not_finite(**values: object) -> str:
    """The values that are not finite numbers, as people read them ("x=nan, y=inf"); "" when
    every one is. Odometry can lie: a position is checked with this wherever it comes in."""
    return ", ".join(f"{name}={value!r:.20}" for name, value in values.items() if not _real(value))


def _real(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def carried(pose: Pose2D, before: RobotState, after: RobotState) -> Pose2D:
    """`pose`, seen in the frame of the state `before`, where the localization jumps between
    `before` and `after` (SLAM's map -> odom) have put it: the same place to odometry."""
    undone = compose(inverse(before.jumps), (pose.x, pose.y, pose.yaw))
    return Pose2D(*compose(after.jumps, undone))


def position_unknown(pose: Pose2D) -> str:
    """Why the robot's pose cannot be used: "the robot's position is unknown (odometry
    reports x=nan)"; "" when it can."""
    bad = pose.unknown()
    return f"the robot's position is unknown (odometry reports {bad})" if bad else ""


@dataclass(frozen=True)
class RobotState:
    """A snapshot of the robot. Velocities are in the body frame (x forward, y left)."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0
    posture: Posture = Posture.STANDING
    battery: float | None = 100.0  # percent; None = unknown (a Go2 without a battery source)
    distance_travelled: float = 0.0  # metres, path length since the robot started
    angle_turned: float = 0.0  # radians, absolute rotation since the robot started
    time_moving: float = 0.0  # seconds the robot has been moving since it started
    stamp: float = 0.0  # seconds on the robot's clock
    estopped: bool = False
    connected: bool = True
    # What stops the body when it presses against something, as people say it ("the red ball
    # 0.35 m ahead"); empty when nothing does or the robot cannot tell.
    blocked_by: str = ""
    # How many times localization has corrected the robot's map pose by more than a step may
    # absorb (SLAM's map -> odom jumped): the pose moved without the robot moving. A leg that
    # sees it change stops (skills.motion); 0 on a robot whose pose has no map correction.
    relocalized: int = 0
    # Those jumps composed (x, y, yaw, in the pose's frame): a place seen before them is at
    # compose(jumps, place) after them. `carried` follows a pose across jumps with it.
    jumps: tuple[float, float, float] = (0.0, 0.0, 0.0)
    # Odometry's own pose (x, y, yaw in its frame), before any map correction; None where the
    # pose is odometry's (no SLAM). What the robot's motion did, whatever SLAM moved the map
    # by meanwhile: the checks of a leg against its commands read it (`own_pose`).
    odometry: tuple[float, float, float] | None = None

    @property
    def pose(self) -> Pose2D:
        return Pose2D(self.x, self.y, self.yaw)

    @property
    def own_pose(self) -> Pose2D:
        """Odometry's pose in its own frame: `pose` without SLAM's map -> odom corrections."""
        return self.pose if self.odometry is None else Pose2D(*self.odometry)

    @property
    def battery_text(self) -> str:
        """The battery level for people: "87.0%", or "unknown" (never a guess)."""
        return "unknown" if self.battery is None else f"{self.battery:.1f}%"

    def in_words(self) -> str:
        """Posture, pose, battery and distance walked as people read them: "Standing at
        x=1.00 m, y=0.00 m, facing 90 degrees; battery 99.9%; travelled 1.00 m in total"."""
        unknown = position_unknown(self.pose)
        facing = f"facing {math.degrees(self.yaw):.0f} degrees"
        where = f", {unknown}" if unknown else f" at x={self.x:.2f} m, y={self.y:.2f} m, {facing}"
        return (
            f"{self.posture.value.capitalize()}{where}; battery {self.battery_text}; "
            f"travelled {self.distance_travelled:.2f} m in total"
        )

    @property
    def is_moving(self) -> bool:
        return abs(self.vx) > 1e-3 or abs(self.vy) > 1e-3 or abs(self.wz) > 1e-3

    def to_dict(self) -> dict[str, Any]:
        """The JSON form used by the CLI, the web API and diagnostics (rounded for people).
        A number the robot reports that is not finite (odometry that lies) is None."""
        return {
            "x": number(self.x, 4),
            "y": number(self.y, 4),
            "yaw": number(self.yaw, 4),
            "yaw_deg": number(math.degrees(self.yaw), 2),
            "posture": self.posture.value,
            "battery": None if self.battery is None else number(self.battery, 2),
            "distance_travelled": number(self.distance_travelled, 4),
            "angle_turned": number(self.angle_turned, 4),
            "time_moving": number(self.time_moving, 2),
            "moving": self.is_moving,
            "estopped": self.estopped,
            "connected": self.connected,
            "blocked_by": self.blocked_by,
            "stamp": number(self.stamp, 3),
        }


@dataclass(frozen=True)
class Sighting:
    """Something in view, as a simulator knows it (ground truth, not a model's guess)."""

    name: str
    distance: float  # metres from the camera
    bearing_deg: float  # + left of centre

    def describe(self) -> str:
        side = "ahead"
        if self.bearing_deg > 8:
            side = f"{abs(self.bearing_deg):.0f} degrees to the left"
        elif self.bearing_deg < -8:
            side = f"{abs(self.bearing_deg):.0f} degrees to the right"
        if not math.isfinite(self.distance):  # a detector's box with no range
            return f"{self.name} {side} (how far is not known)"
        return f"{self.name} about {self.distance:.1f} m {side}"


@dataclass(frozen=True)
class CameraFrame:
    """One camera image. `encoding` is jpeg or png (compressed bytes) or rgb8/bgr8/mono8 (raw)."""

    data: bytes
    width: int
    height: int
    encoding: str
    stamp: float = field(default_factory=time.time)  # wall-clock seconds when received
    source: str = "camera"
    sightings: tuple[Sighting, ...] = ()  # only a simulator fills this

    def summary(self) -> dict[str, Any]:
        out = asdict(self)
        out.pop("data")
        out["bytes"] = len(self.data)
        out["sightings"] = [s.describe() for s in self.sightings]
        return out


@dataclass(frozen=True)
class Scan:
    """A planar range scan in the layout of sensor_msgs/LaserScan, taken at `pose` (odom frame).

    Beam i points at `pose.yaw + angle_min + i * angle_increment`. A range outside
    [range_min, range_max] (or infinite) means no return within reach on that beam.
    """

    ranges: tuple[float, ...]
    angle_min: float = -math.pi
    angle_increment: float = 2.0 * math.pi / 360
    range_min: float = 0.1
    range_max: float = 8.0
    pose: Pose2D = field(default_factory=Pose2D)
    stamp: float = 0.0  # seconds on the robot's clock

    def __post_init__(self) -> None:
        if not self.ranges:
            raise ValueError("a scan needs at least one beam")
        if not 0 <= self.range_min < self.range_max or not math.isfinite(self.range_max):
            raise ValueError(
                f"need 0 <= range_min < range_max (finite), got {self.range_min}, {self.range_max}"
            )
        if not self.angle_increment > 0:
            raise ValueError(f"angle_increment must be > 0, got {self.angle_increment}")

    def beam_angle(self, i: int) -> float:
        """The beam's direction in the odom frame, radians."""
        return self.pose.yaw + self.angle_min + i * self.angle_increment

    def is_hit(self, r: float) -> bool:
        """Whether a range is a real return (an obstacle surface), not a miss or an error."""
        return self.range_min <= r < self.range_max
