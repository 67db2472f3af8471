"""How much of each ROS input a robot takes, and the record of what it refused or cut (pure
Python; the subscriptions that apply it are ros_inputs.py, the stamps' window go2/stamps.py).

A message may carry whatever its type allows: 1,000 boxes, a million scan beams, thousands of
transforms. Read on the executor thread that also reads odometry, a big one starves the control
path (issue 32: rclpy took 0.2 s to read each 1,000-box Detection2DArray; odometry stopped for
0.5 s, and Nav2's goals were not accepted). So every input has a limit, far above what an
honest robot sends (a house's map, a lidar's scan, a detector's boxes):

- bytes: a message larger than its kind's limit is refused before it is read (`MAX_BYTES`), so
  no sender can make one message cost more than that;
- items: of a detection message the `MAX_BOXES` most confident are kept; a scan of more than
  `MAX_BEAMS` ranges is refused (world_msgs.scan_from_msg); a map of more than the grid's
  MAX_CELLS too (world/grid.py);
- time: what is read off the executor is read at most `READ_SHARE` of its thread's time.
"""

from __future__ import annotations

import heapq
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TypeVar

from ..world.grid import MAX_CELLS

T = TypeVar("T")

MAX_BOXES = 100  # detections per message kept (the most confident): a COCO model finds <= 100
# The most of its time a thread reading maps, images, detections or TF spends reading
# (handoff.py): a flood costs the process a quarter of a processor, and odometry's callbacks
# wait for the interpreter that much less. A detector's few boxes take a millisecond to read,
# 100 boxes 12 ms (read at up to 20 Hz then), robot_state_publisher's 30 links 1.5 ms, a 1080p
# image 3 ms, on a quiet machine (bench/RESULTS.md).
READ_SHARE = 0.25
MAX_BEAMS = 10_000  # ranges per LaserScan: a lidar's scan is a few thousand at most
_KB = 1024
_MB = 1024 * _KB
# Serialized bytes per message, by kind. A box is about 430 bytes (one hypothesis with its
# covariance), a transform about 100, a scan beam 8 (range and intensity), a map cell 1. rclpy
# holds the interpreter while it reads a message, every thread of the process waiting (and a
# loaded machine may stop the reader meanwhile): 0.12 ms a box, 0.05 ms a transform on a quiet
# machine, five times that on a loaded one (bench/RESULTS.md). The limits of what it reads item
# by item keep one read to some 20 ms; arrays (a scan, a map, an image) read at memory speed.
MAX_BYTES = {
    "small": 64 * _KB,  # odometry, go2_states, battery, camera_info: fixed size but strings
    "detections": 64 * _KB,  # about 150 boxes, the 100 most confident read; coco_detector's
    # threshold (0.9) leaves a few, YOLO's (0.25) some dozens
    "tf": 32 * _KB,  # about 300 transforms; robot_state_publisher sends a Go2's 30 in 3 KB
    "scan": 8 * MAX_BEAMS + 64 * _KB,
    "map": MAX_CELLS + 64 * _KB,  # 250 m x 250 m at 5 cm
    "image": 50 * _MB,  # a 4K rgb8 frame is 25 MB; a JPEG far less
}


def size_words(size: int) -> str:
    """Bytes as people read them: 512 bytes, 64 KB, 1.5 MB."""
    if size < _KB:
        return f"{size} bytes"
    if size < _MB:
        return f"{size / _KB:.0f} KB"
    return f"{size / _MB:.1f} MB"


def most_confident(items: Iterable[T], score: Callable[[T], float], limit: int) -> list[T]:
    """The `limit` items of highest `score`, in their order (all of them when there are fewer);
    time linear in the items."""
    listed = list(items)
    if len(listed) <= limit:
        return listed
    keep = {id(i) for i in heapq.nlargest(limit, listed, key=score)}
    return [i for i in listed if id(i) in keep]


@dataclass(frozen=True)
class InputProblem:
    """One kind of refusal on one topic: the latest words, how often, and when (monotonic)."""

    topic: str
    kind: str
    text: str
    count: int
    last: float

    def words(self) -> str:
        times = f" ({self.count} times)" if self.count > 1 else ""
        return f"{self.topic}: {self.text}{times}"


class InputReport:
    """What the robot refused or cut of its inputs, per (topic, kind); thread-safe."""

    def __init__(self, quiet: float = 30.0, recent: float = 60.0) -> None:
        """`quiet`: seconds between log lines of one kind; `recent`: seconds a problem stays in
        `summary` after it last happened."""
        self.quiet, self.recent = quiet, recent
        self._lock = threading.Lock()
        self._problems: dict[tuple[str, str], InputProblem] = {}
        self._logged: dict[tuple[str, str], float] = {}

    def note(self, topic: str, kind: str, text: str, now: float) -> bool:
        """Record one refusal (`now`: monotonic seconds). True when it should be logged: its
        kind is new on the topic, or was last logged `quiet` seconds ago."""
        key = (topic, kind)
        with self._lock:
            was = self._problems.get(key)
            count = was.count + 1 if was else 1
            self._problems[key] = InputProblem(topic, kind, text, count, now)
            if now - self._logged.get(key, -self.quiet - 1.0) < self.quiet:
                return False
            self._logged[key] = now
            return True

    def problems(self) -> tuple[InputProblem, ...]:
        with self._lock:
            return tuple(self._problems.values())

    def summary(self, now: float) -> str:
        """The problems of the last `recent` seconds, newest first, for diagnostics ('' none)."""
        recent = [p for p in self.problems() if now - p.last <= self.recent]
        return "; ".join(p.words() for p in sorted(recent, key=lambda p: -p.last))
