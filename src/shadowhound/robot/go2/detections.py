"""Detections from any detector -> sightings in the robot's world model.

Two kinds: positions, and boxes in an image. A detector publishes
shadowhound_interfaces/DetectionArray (docs/ros.md, "Detections"); the Go2 robot subscribes it
when `detections_topic` is set. A 2-D detector (go2_ros2_sdk's coco_detector) publishes
vision_msgs/Detection2DArray, subscribed when `coco_detections_topic` is set: `BoxIntake` turns
its boxes into sightings with camera_info, odometry and the scan (world/image_sighting.py).
Positions become KnownObjects in the odometry frame: positions in the odometry frame are taken
as they are, positions in the robot's body frame are placed with the robot's pose when the
detection arrives. Other frames would need tf, which the project does not use: they are
refused, with a message naming the frames allowed, and nothing else in the array is lost.

Of one message the MAX_BOXES most confident detections are read (a model may send thousands:
issue 32), and a detection stamped outside the StampWindow of the node's clock (from the future:
its sighting would stay "latest" and in view; too old: no pose is kept for it) is refused. What
a message lost so is its `Reading.notes`, which the robot reports (input_limits.InputReport).

Pure Python (messages are read by attribute), so the rules are tested without ROS.
"""

from __future__ import annotations

import math
import threading
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any

from ...errors import DetectionError
from ...state import Pose2D, Scan
from ...world.image_sighting import (
    Bearing,
    BoxDetection,
    CameraModel,
    PoseHistory,
    SightingRules,
    locate,
    nearest_scan,
    planner_name,
)
from ...world.objects import KnownObject, merge_sightings
from ..input_limits import MAX_BOXES, most_confident
from .stamps import STAMPS, StampWindow

DEFAULT_RADIUS = 0.25  # metres, a detection that gives no footprint
MAX_LABEL = 100  # characters; a label is a name people say, not a paragraph
MAX_OBJECTS = 500  # distinct names kept; beyond this the oldest sighting is forgotten


@dataclass
class Reading:
    """What one detection message gave: sightings, bearings (boxes with no range), what was
    refused of single detections (`problems`), and what the message lost as a whole (`notes`:
    (kind, words) of a cap or of stamps out of the window, for the robot's input report)."""

    seen: list[KnownObject] = field(default_factory=list)
    bearings: list[Bearing] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    notes: list[tuple[str, str]] = field(default_factory=list)


def _capped(detections: Any, score: Any, notes: list[tuple[str, str]]) -> list[Any]:
    """The MAX_BOXES most confident of a message's detections, noting a cut."""
    items = list(detections)
    kept = most_confident(items, score, MAX_BOXES)
    if len(kept) < len(items):
        notes.append(
            (
                "too many",
                f"{len(items)} detections in one message: read the {MAX_BOXES} most confident",
            )
        )
    return kept


def _refuse_stamp(
    stamp: float, now: float, what: str, window: StampWindow, notes: list[tuple[str, str]]
) -> bool:
    """Whether `stamp` is outside the window at `now`, noting why."""
    problem = window.problem(stamp, now)
    if problem is not None:
        notes.append(("stamp", f"{what} {problem}: refused"))
    return problem is not None


@dataclass(frozen=True)
class Frames:
    """The frames a detection may be given in: the robot's odometry frame and its body frame
    (go2_ros2_sdk: `odom` and `base_link`; the odometry message's own frame ids win)."""

    odom: str = "odom"
    body: str = "base_link"
    # With SLAM: the map frame, and where odom sits in it (map -> odom, x, y, yaw) when the
    # detection arrived. Sightings are then kept in the map: odom positions are carried over.
    map: str = ""
    odom_in_map: tuple[float, float, float] | None = None


def to_sighting(
    label: str,
    x: float,
    y: float,
    frame: str,
    confidence: float,
    radius: float,
    stamp: float,
    pose: Pose2D,
    frames: Frames,
) -> KnownObject:
    """One detection as a sighting in the robot's world frame: SLAM's map when `frames` has one
    (with map -> odom), else the odometry frame. `pose` is the robot's pose in that frame (used
    for body-frame positions); `stamp` is in robot-clock seconds."""
    name = " ".join(str(label).split())
    if not name:
        raise DetectionError("a detection needs a label (what it is, e.g. 'red ball')")
    if len(name) > MAX_LABEL:
        raise DetectionError(
            f"label {name[:40]!r}... is {len(name)} characters; at most {MAX_LABEL} are allowed"
        )
    if not (math.isfinite(x) and math.isfinite(y)):
        raise DetectionError(f"{name!r}: position must be finite metres, got ({x}, {y})")
    if not (math.isfinite(confidence) and 0.0 <= confidence <= 1.0):
        raise DetectionError(f"{name!r}: confidence must be between 0 and 1, got {confidence}")
    if not (math.isfinite(radius) and 0.0 <= radius <= 10.0):
        raise DetectionError(f"{name!r}: radius must be 0 (unknown) to 10 m, got {radius}")
    frame = frame.strip().lstrip("/")
    if frames.map and frame == frames.map:
        wx, wy = x, y
    elif frame == frames.odom:
        wx, wy = x, y
        if frames.odom_in_map is not None:
            mx, my, myaw = frames.odom_in_map
            c, s = math.cos(myaw), math.sin(myaw)
            wx, wy = mx + c * x - s * y, my + s * x + c * y
    elif frame == frames.body:
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        wx, wy = pose.x + c * x - s * y, pose.y + s * x + c * y
    else:
        raise DetectionError(
            f"{name!r}: frame {frame or '(empty)'!r} is not supported; give "
            f"positions in {frames.odom!r} (the odometry frame)"
            + (f", {frames.map!r} (SLAM's map)" if frames.map else "")
            + f" or {frames.body!r} (the robot's body)"
        )
    return KnownObject(name, wx, wy, radius or DEFAULT_RADIUS, confidence, stamp)


def sightings_from_msg(
    msg: Any,
    pose: Pose2D,
    frames: Frames,
    now: float,
    clock: float,
    window: StampWindow = STAMPS,
) -> Reading:
    """A DetectionArray as sightings, and what was refused. `now` is the robot clock, `clock`
    the node's ROS clock the stamps are on (a zero stamp counts as `clock`)."""
    out = Reading()
    default_frame = str(msg.header.frame_id)
    for d in _capped(msg.detections, lambda d: float(d.confidence), out.notes):
        frame = str(d.header.frame_id) or default_frame
        stamp = (
            d.header.stamp if (d.header.stamp.sec or d.header.stamp.nanosec) else msg.header.stamp
        )
        at = _seconds(stamp) if (stamp.sec or stamp.nanosec) else clock
        if _refuse_stamp(at, clock, f"a detection ({str(d.label)[:40]!r})", window, out.notes):
            continue
        try:
            out.seen.append(
                to_sighting(
                    str(d.label),
                    float(d.position.x),
                    float(d.position.y),
                    frame,
                    float(d.confidence),
                    float(d.radius),
                    now - max(0.0, clock - at),
                    pose,
                    frames,
                )
            )
        except DetectionError as exc:
            out.problems.append(str(exc))
    return out


class SightingBoard:
    """The sightings a robot has had from its detections, one per name, safe across threads."""

    def __init__(self, limit: int = MAX_OBJECTS) -> None:
        self._lock = threading.Lock()
        self._objects: tuple[KnownObject, ...] = ()
        self._limit = limit

    def add(self, seen: Iterable[KnownObject]) -> None:
        with self._lock:
            merged = merge_sightings(self._objects, seen)
            if len(merged) > self._limit:  # forget the longest unseen
                merged = tuple(sorted(merged, key=lambda o: o.stamp)[-self._limit :])
            self._objects = merged

    def objects(self) -> tuple[KnownObject, ...]:
        with self._lock:
            return self._objects


# -- boxes in an image (vision_msgs/Detection2DArray, go2_ros2_sdk's coco_detector) ------------

# The COCO category names coco_detector reports (its model's 80 classes), as the planner's
# words: what a search may look for with a COCO detector.
_COCO = (
    "person, bicycle, car, motorcycle, airplane, bus, train, truck, boat, traffic light, "
    "fire hydrant, stop sign, parking meter, bench, bird, cat, dog, horse, sheep, cow, "
    "elephant, bear, zebra, giraffe, backpack, umbrella, handbag, tie, suitcase, frisbee, "
    "skis, snowboard, sports ball, kite, baseball bat, baseball glove, skateboard, "
    "surfboard, tennis racket, bottle, wine glass, cup, fork, knife, spoon, bowl, banana, "
    "apple, sandwich, orange, broccoli, carrot, hot dog, pizza, donut, cake, chair, couch, "
    "potted plant, bed, dining table, toilet, tv, laptop, mouse, remote, keyboard, "
    "cell phone, microwave, oven, toaster, sink, refrigerator, book, clock, vase, "
    "scissors, teddy bear, hair drier, toothbrush"
)
COCO_CLASSES = tuple(planner_name(name) for name in _COCO.split(", "))
MAX_BEARINGS = 50  # bearing-only sightings kept (the latest), for diagnostics
HOLD_SECONDS = 2.0  # image seconds a box waits for the odometry of its time
MAX_HELD = 100  # boxes waiting at most


@dataclass(frozen=True)
class CameraMount:
    """Where the camera sits on the robot: `x` forward, `y` left (metres from base_link) and
    `yaw` (radians left of the heading). The Go2's front camera is at its nose, about 0.3 m
    ahead of base_link (take the exact figures from the robot's URDF)."""

    x: float = 0.3
    y: float = 0.0
    yaw: float = 0.0


def _seconds(stamp: Any) -> float:
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def _best_score(d: Any) -> float:
    """A box's confidence: its most likely class's score (0 without one)."""
    return max((float(r.hypothesis.score) for r in d.results), default=0.0)


class BoxIntake:
    """vision_msgs/Detection2DArray -> sightings, with the camera model from camera_info, the
    robot's poses from odometry and the scans that range the boxes, all by their stamps (the
    ROS clock of the headers; an odometry pose by the time it was the robot's, which late
    odometry stamps later). Thread-safe; messages are read by attribute (no rclpy)."""

    def __init__(
        self,
        mount: CameraMount = CameraMount(),
        rules: SightingRules | None = None,
        window: StampWindow = STAMPS,
    ) -> None:
        self._lock = threading.Lock()
        self._mount = mount
        self._rules = rules or SightingRules()
        self._window = window
        self._camera: CameraModel | None = None
        self._poses = PoseHistory()
        self._scans: deque[Scan] = deque(maxlen=20)
        self._bearings: deque[Bearing] = deque(maxlen=MAX_BEARINGS)
        self._held: deque[BoxDetection] = deque(maxlen=MAX_HELD)

    def on_camera_info(self, k: Any) -> str | None:
        """camera_info's K (row-major 3x3): fx = K[0], cx = K[2]. A problem, or None."""
        try:
            camera = CameraModel(
                float(k[0]), float(k[2]), self._mount.x, self._mount.y, self._mount.yaw
            )
        except (IndexError, TypeError, ValueError) as exc:
            return f"camera_info without a usable K (fx, cx): {exc}"
        with self._lock:
            self._camera = camera
        return None

    def on_pose(self, stamp: float, pose: Pose2D, now: float) -> str | None:
        """The robot's pose at `stamp` (when it was there: odometry's stamp less its lag),
        received at `now` (the node's ROS clock). Returns why it was refused (a stamp outside
        the window: kept, the latest by stamp would hold off every honest pose), or None."""
        problem = self._window.problem(stamp, now)
        if problem is None:
            with self._lock:
                self._poses.add(stamp, pose)
        return problem

    def on_scan(self, stamp: float, scan: Scan, now: float) -> str | None:
        """A scan taken at `stamp`, received at `now`; placed at the robot's pose then when a
        box needs it (its own pose only when the history has none for it). Returns why it was
        refused (a stamp outside the window), or None."""
        problem = self._window.problem(stamp, now)
        if problem is None:
            with self._lock:
                self._scans.append(replace(scan, stamp=stamp))
        return problem

    @property
    def has_camera(self) -> bool:
        with self._lock:
            return self._camera is not None

    def bearings(self) -> tuple[Bearing, ...]:
        """The latest bearing-only sightings (kept as hints, never goals)."""
        with self._lock:
            return tuple(self._bearings)

    def read(self, msg: Any, now: float) -> Reading:
        """A Detection2DArray as sightings (stamped with the image's header time), bearings
        (no range, or beyond max_range) and what was refused; `now` is the node's ROS clock,
        which the stamps are on. A box seen while the robot moved, before odometry (late)
        reached its time, waits for it: it comes out of a later read, placed by the pose it was
        seen from, or is refused after HOLD_SECONDS. Placed by the last pose instead, a box
        seen while turning lands tens of centimetres off."""
        out = Reading()
        with self._lock:
            camera = self._camera
        if camera is None:
            out.problems.append("no camera_info yet: the boxes cannot be turned into bearings")
            return out
        image = _seconds(msg.header.stamp)
        if _refuse_stamp(image, now, "an image's boxes", self._window, out.notes):
            return out
        boxes = []
        for d in _capped(msg.detections, _best_score, out.notes):
            stamp = d.header.stamp if (d.header.stamp.sec or d.header.stamp.nanosec) else None
            if not d.results:
                out.problems.append("a detection without a class (results is empty)")
                continue
            best = max(d.results, key=lambda r: float(r.hypothesis.score))
            at = _seconds(stamp) if stamp is not None else image
            if _refuse_stamp(
                at, now, f"a box ({str(best.hypothesis.class_id)[:40]!r})", self._window, out.notes
            ):
                continue
            boxes.append(
                BoxDetection(
                    str(best.hypothesis.class_id),
                    float(d.bbox.center.position.x),
                    float(d.bbox.size_x),
                    float(best.hypothesis.score),
                    at,
                )
            )
        for box, pose, scan in self._ready(boxes, image):
            if pose is None:
                out.problems.append(
                    f"{box.label!r}: no odometry pose at the image's time {box.stamp:.2f}"
                )
                continue
            try:
                found = locate(box, camera, pose, scan, self._rules)
            except ValueError as exc:
                out.problems.append(str(exc))
                continue
            if isinstance(found, Bearing):
                out.bearings.append(found)
            else:
                out.seen.append(found)
        with self._lock:
            self._bearings.extend(out.bearings)
        return out

    def _ready(
        self, boxes: list[BoxDetection], now: float
    ) -> list[tuple[BoxDetection, Pose2D | None, Scan | None]]:
        """The boxes held and `boxes` whose time odometry has reached (their scan's too), with
        the pose and the scan (placed) of that time; the rest held, up to HOLD_SECONDS before
        `now` (image time), then given no pose."""
        out: list[tuple[BoxDetection, Pose2D | None, Scan | None]] = []
        with self._lock:
            waiting = [*self._held, *boxes]
            self._held.clear()
            now = max([now, *(b.stamp for b in waiting)])
            for box in waiting:
                scan = nearest_scan(tuple(self._scans), box.stamp, self._rules.scan_slack)
                known = self._poses.known(box.stamp) and (
                    scan is None or self._poses.known(scan.stamp)
                )
                if not known and now - box.stamp <= HOLD_SECONDS:
                    self._held.append(box)
                    continue
                if scan is not None:
                    scan = replace(scan, pose=self._poses.at(scan.stamp) or scan.pose)
                out.append((box, self._poses.at(box.stamp) if known else None, scan))
        return out
