"""A box in a camera image (a 2-D detector's, e.g. go2_ros2_sdk's coco_detector) as a sighting.

The box gives a direction only: its centre column through a pinhole camera model (fx, cx of
camera_info's K) is a bearing from the camera, which is mounted on the robot at (x, y, yaw) in
base_link. The distance comes from a laser scan taken at about the image's time: the median
distance, from the camera, of the scan's returns that fall within the box's angular width; the
centre is where those returns put the centre of a round object as wide as the box. The robot's
pose at the image's time comes from odometry history. Without such a scan, with no return in
the box, or farther than `max_range`, the result is a `Bearing`: kept as a hint of a direction,
never a place to go.

Pure Python (no rclpy): the Go2 backend feeds it messages read by attribute, tests feed it
dataclasses.
"""

from __future__ import annotations

import bisect
import math
import statistics
from collections import deque
from dataclasses import dataclass

from ..state import Pose2D, Scan, compose, normalize_angle
from .objects import COCO_NAMES, KnownObject

STILL = 0.005  # metres (and radians) between the last two poses of a robot at rest
MIN_RADIUS = 0.1  # metres: the smallest footprint a sighting is given
MAX_RADIUS = 1.5  # metres: the largest (as the map's own estimate, world/objects.py)


def planner_name(class_id: str) -> str:
    """A detector's class name as the planner says it: "tv" -> "television" (`COCO_NAMES`;
    names compare the same either way, `object_key`)."""
    key = " ".join(class_id.strip().lower().replace("_", " ").split())
    return COCO_NAMES.get(key, key)


@dataclass(frozen=True)
class CameraModel:
    """A pinhole camera's horizontal geometry: focal length `fx` and principal point `cx` in
    pixels (camera_info K[0] and K[2]), mounted at (`x` forward, `y` left) metres from
    base_link, looking `yaw` radians left of the robot's heading."""

    fx: float
    cx: float
    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.fx) and self.fx > 0):
            raise ValueError(f"camera fx must be > 0 pixels, got {self.fx}")
        for name in ("cx", "x", "y", "yaw"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"camera {name} must be finite, got {getattr(self, name)}")

    def angle_of(self, u: float) -> float:
        """The direction of image column `u` from the camera's axis, radians, left positive
        (columns grow to the right)."""
        return math.atan2(self.cx - u, self.fx)

    def column_of(self, angle: float) -> float:
        """The image column a direction `angle` from the camera's axis (left positive) falls
        on; the inverse of `angle_of` for |angle| < pi/2."""
        return self.cx - self.fx * math.tan(angle)

    def origin(self, pose: Pose2D) -> Pose2D:
        """The camera's own pose in the odometry frame when the robot stands at `pose`."""
        return Pose2D(*compose((pose.x, pose.y, pose.yaw), (self.x, self.y, self.yaw)))


@dataclass(frozen=True)
class BoxDetection:
    """One detection in an image: class name, box centre column `u` and `width` in pixels,
    `score` 0..1, and the image's `stamp` (seconds, the clock odometry and scans are on)."""

    label: str
    u: float
    width: float
    score: float
    stamp: float


@dataclass(frozen=True)
class Bearing:
    """Something seen in a direction at an unknown (or too great) distance: from (x, y) in the
    odometry frame, towards `direction` (radians). A hint only: never a goal."""

    name: str
    x: float
    y: float
    direction: float
    confidence: float
    stamp: float
    why: str


@dataclass(frozen=True)
class SightingRules:
    """How far a box may be placed (`max_range` metres from the camera), how far apart in time
    an image and the scan that ranges it may be (`scan_slack` seconds), and how many returns
    the box needs (`min_returns`)."""

    max_range: float = 6.0
    scan_slack: float = 0.3
    min_returns: int = 1


class PoseHistory:
    """The robot's recent poses by stamp (odometry), for the pose at an image's stamp."""

    def __init__(self, window: float = 10.0, slack: float = 0.3) -> None:
        self._stamps: deque[float] = deque()
        self._poses: deque[Pose2D] = deque()
        self._window = window
        self._slack = slack

    def add(self, stamp: float, pose: Pose2D) -> None:
        """A pose at `stamp`; an older stamp than the last one restarts the history (a clock
        that jumped back, e.g. a restarted simulation)."""
        if self._stamps and stamp < self._stamps[-1]:
            self._stamps.clear()
            self._poses.clear()
        self._stamps.append(stamp)
        self._poses.append(pose)
        while self._stamps and self._stamps[0] < stamp - self._window:
            self._stamps.popleft()
            self._poses.popleft()

    def known(self, stamp: float) -> bool:
        """Whether the pose at `stamp` can be told now: the history reaches it, or it ends at
        rest (its last two poses alike), where a later stamp finds the robot still. Late
        odometry reaches a moving robot's present only later: until then its last pose is where
        the robot was, not where it is."""
        stamps, poses = self._stamps, self._poses
        if not stamps:
            return False
        if stamp <= stamps[-1]:
            return True
        if len(stamps) < 2:
            return False
        a, b = poses[-2], poses[-1]
        return (
            math.hypot(b.x - a.x, b.y - a.y) < STILL and abs(normalize_angle(b.yaw - a.yaw)) < STILL
        )

    def at(self, stamp: float) -> Pose2D | None:
        """The pose at `stamp`, interpolated between the poses around it; the nearest one up
        to `slack` seconds beyond either end; None beyond that (no pose known then)."""
        stamps = self._stamps
        if not stamps or not (stamps[0] - self._slack <= stamp <= stamps[-1] + self._slack):
            return None
        i = bisect.bisect_left(stamps, stamp)
        if i == 0:
            return self._poses[0]
        if i == len(stamps):
            return self._poses[-1]
        t0, t1 = stamps[i - 1], stamps[i]
        a, b = self._poses[i - 1], self._poses[i]
        f = 0.0 if t1 <= t0 else (stamp - t0) / (t1 - t0)
        return Pose2D(
            a.x + f * (b.x - a.x),
            a.y + f * (b.y - a.y),
            normalize_angle(a.yaw + f * normalize_angle(b.yaw - a.yaw)),
        )


def nearest_scan(scans: list[Scan] | tuple[Scan, ...], stamp: float, slack: float) -> Scan | None:
    """The scan taken nearest `stamp`, if within `slack` seconds of it."""
    best = min(scans, key=lambda s: abs(s.stamp - stamp), default=None)
    return best if best is not None and abs(best.stamp - stamp) <= slack else None


def box_returns(scan: Scan, camera: Pose2D, left: float, right: float) -> list[tuple[float, float]]:
    """The scan's returns whose direction from the camera (at `camera`, odometry frame) lies
    between `right` and `left` (radians from the camera's axis): (distance from the camera,
    direction from its axis) each."""
    found = []
    for i, r in enumerate(scan.ranges):
        if not scan.is_hit(r):
            continue
        a = scan.beam_angle(i)
        hx, hy = scan.pose.x + r * math.cos(a), scan.pose.y + r * math.sin(a)
        dx, dy = hx - camera.x, hy - camera.y
        along = normalize_angle(math.atan2(dy, dx) - camera.yaw)
        if right <= along <= left:
            found.append((math.hypot(dx, dy), along))
    return found


def centre_distance(returns: list[tuple[float, float]], middle: float, radius: float) -> float:
    """How far from the camera, along the direction `middle` (from its axis), stands the centre
    of a round object of `radius` whose near face gave `returns` (distance, direction): the
    median of where each return puts it. A return off the middle lies behind the face's closest
    point; taking the median return as that point (and the centre one radius behind it) puts the
    centre too far, by about an eighth of the radius, and a robot that stands off from it too
    close. Returns farther off the middle than the radius (not on the object) are not used."""
    centres = []
    for d, a in returns:
        off = d * math.sin(a - middle)
        if abs(off) < radius:
            centres.append(d * math.cos(a - middle) + math.sqrt(radius * radius - off * off))
    if not centres:  # nothing on the circle: its closest point is the median return
        return statistics.median(d for d, _ in returns) + radius
    return statistics.median(centres)


def locate(
    detection: BoxDetection,
    camera: CameraModel,
    pose: Pose2D,
    scan: Scan | None,
    rules: SightingRules = SightingRules(),
) -> KnownObject | Bearing:
    """Where `detection` is, seen by `camera` with the robot at `pose` (its pose at the image's
    stamp) and ranged by `scan` (taken at about that stamp, or None): a sighting (a KnownObject
    in the odometry frame, its centre where the returns on its near face put a round object as
    wide as the box at that distance) or, without a usable range, a Bearing."""
    name = planner_name(detection.label)
    if not name:
        raise ValueError("a detection needs a class name")
    if not (math.isfinite(detection.u) and math.isfinite(detection.width) and detection.width >= 0):
        raise ValueError(f"{name!r}: the box's centre and width must be finite pixels")
    eye = camera.origin(pose)
    left = camera.angle_of(detection.u - detection.width / 2)
    right = camera.angle_of(detection.u + detection.width / 2)
    # Halfway between the edges' directions, not the centre column's: off the axis the image
    # stretches, and the column halfway is no longer the object's middle.
    middle = (left + right) / 2
    direction = normalize_angle(eye.yaw + middle)
    confidence = min(1.0, max(0.0, detection.score))

    def bearing(why: str) -> Bearing:
        return Bearing(name, eye.x, eye.y, direction, confidence, detection.stamp, why)

    if scan is None:
        return bearing("no scan at the image's time")
    returns = box_returns(scan, eye, left, right)
    if not returns or len(returns) < rules.min_returns:
        return bearing("no laser return within the box")
    distance = statistics.median(d for d, _ in returns)
    if distance > rules.max_range:
        return bearing(f"{distance:.1f} m away, beyond {rules.max_range:g} m")
    # A round object of radius R whose near surface is `distance` away fills sin(h) = R /
    # (distance + R) of the view's half-angle h.
    s = min(0.9, math.sin(max(0.0, (left - right) / 2)))
    radius = min(MAX_RADIUS, max(MIN_RADIUS, distance * s / (1 - s)))
    # The median return lies behind the closest point: the radius it gives is a little large.
    # The centre it places gives the radius again (sin(h) = R / centre's distance), once.
    radius = min(MAX_RADIUS, max(MIN_RADIUS, centre_distance(returns, middle, radius) * s))
    reach = centre_distance(returns, middle, radius)
    return KnownObject(
        name,
        eye.x + reach * math.cos(direction),
        eye.y + reach * math.sin(direction),
        radius,
        confidence,
        detection.stamp,
    )
