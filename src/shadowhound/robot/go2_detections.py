"""Detections from any detector -> sightings in the robot's world model.

A detector publishes shadowhound_interfaces/DetectionArray (docs/ros.md, "Detections"); the
Go2 robot subscribes it when `detections_topic` is set. Each detection becomes a KnownObject in
the odometry frame: positions in the odometry frame are taken as they are, positions in the
robot's body frame are placed with the robot's pose when the detection arrives. Other frames
would need tf, which the project does not use: they are refused, with a message naming the
frames allowed, and nothing else in the array is lost.

Pure Python (messages are read by attribute), so the rules are tested without ROS.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from ..errors import DetectionError
from ..state import Pose2D
from ..world.objects import KnownObject, merge_sightings

DEFAULT_RADIUS = 0.25  # metres, a detection that gives no footprint
MAX_LABEL = 100  # characters; a label is a name people say, not a paragraph
MAX_OBJECTS = 500  # distinct names kept; beyond this the oldest sighting is forgotten


@dataclass(frozen=True)
class Frames:
    """The frames a detection may be given in: the robot's odometry frame and its body frame
    (go2_ros2_sdk: `odom` and `base_link`; the odometry message's own frame ids win)."""

    odom: str = "odom"
    body: str = "base_link"


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
    """One detection as a sighting in the odometry frame. `pose` is the robot's pose in that
    frame (used for body-frame positions); `stamp` is in robot-clock seconds."""
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
    if frame == frames.odom:
        wx, wy = x, y
    elif frame == frames.body:
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        wx, wy = pose.x + c * x - s * y, pose.y + s * x + c * y
    else:
        raise DetectionError(
            f"{name!r}: frame {frame or '(empty)'!r} is not supported; give "
            f"positions in {frames.odom!r} (the odometry frame) or "
            f"{frames.body!r} (the robot's body)"
        )
    return KnownObject(name, wx, wy, radius or DEFAULT_RADIUS, confidence, stamp)


def sightings_from_msg(
    msg: Any, pose: Pose2D, frames: Frames, now: float, age: Any
) -> tuple[list[KnownObject], list[str]]:
    """A DetectionArray as sightings, and what was refused. `age(header_stamp)` is how many
    seconds ago a stamp was (0 for a zero stamp); `now` is the robot clock."""
    seen: list[KnownObject] = []
    problems: list[str] = []
    default_frame = str(msg.header.frame_id)
    for d in msg.detections:
        frame = str(d.header.frame_id) or default_frame
        stamp = (
            d.header.stamp if (d.header.stamp.sec or d.header.stamp.nanosec) else msg.header.stamp
        )
        try:
            seen.append(
                to_sighting(
                    str(d.label),
                    float(d.position.x),
                    float(d.position.y),
                    frame,
                    float(d.confidence),
                    float(d.radius),
                    now - max(0.0, float(age(stamp))),
                    pose,
                    frames,
                )
            )
        except DetectionError as exc:
            problems.append(str(exc))
    return seen, problems


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
