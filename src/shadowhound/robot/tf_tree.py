"""The robot's frames in the plane, as tf2 keeps them, without rclpy: map -> odom -> base_link.

SLAM (slam_toolbox, AMCL) publishes map -> odom, a correction that changes when it relocalizes;
the driver publishes odom -> base_link, smooth but drifting; robot_state_publisher publishes
static transforms (base_link -> the camera, the lidar). `TfTree` keeps each dynamic edge as a
short time-stamped history and each static edge once, and answers:

- `lookup(target, source, stamp)`: the transform that takes poses in `source` into `target`
  (tf2's `lookupTransform(target, source, time)`), interpolated between the two samples around
  `stamp` (position linearly, yaw along the shorter arc, as tf2's slerp does in the plane);
- `map_to_odom_jump(since)`: how far the map -> odom correction has moved the robot's map pose
  since `since`, when that is more than the thresholds, so a running step can stop or re-plan;
- `to_odom` / `to_map`: a `Pose2D` carried between map and odom.

Each edge's latest sample is the one with the newest stamp, so a stamp from the future would win
over every honest sample after it (SLAM's corrections ignored from then on): a sample comes with
the time it arrived (`now`, this computer's ROS clock) and one stamped beyond the `StampWindow`
(more than 2 s ahead of it, or older than the history kept) is refused with the reason.

Poses and transforms are 2-D (x, y, yaw): the Go2 walks on a floor, and that is all the agent's
belief uses. No clock of its own: every sample and question carries its stamp (seconds).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

from ..errors import TransformUnavailable
from ..state import Pose2D, compose, normalize_angle, not_finite
from .go2.stamps import STAMP_AHEAD, StampWindow

MAP, ODOM, BASE = "map", "odom", "base_link"


@dataclass(frozen=True)
class Transform2D:
    """A rigid motion of the plane: rotate by `yaw`, then move by (x, y). As the transform of a
    child frame in its parent, it takes coordinates in the child into the parent."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    @classmethod
    def of(cls, pose: Pose2D) -> Transform2D:
        """The transform whose child frame sits at `pose`."""
        return cls(pose.x, pose.y, pose.yaw)

    def compose(self, other: Transform2D) -> Transform2D:
        """`self` after `other`: parent<-middle composed with middle<-child is parent<-child
        (the pose `other` moved into `self`'s frame: state.compose)."""
        return Transform2D(*compose((self.x, self.y, self.yaw), (other.x, other.y, other.yaw)))

    def inverse(self) -> Transform2D:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Transform2D(-c * self.x - s * self.y, s * self.x - c * self.y, -self.yaw)

    def apply(self, pose: Pose2D) -> Pose2D:
        """`pose`, given in the child frame, in the parent frame."""
        moved = self.compose(Transform2D.of(pose))
        return Pose2D(moved.x, moved.y, moved.yaw)


def interpolate(a: Transform2D, b: Transform2D, fraction: float) -> Transform2D:
    """The transform `fraction` (0..1) of the way from `a` to `b`; yaw along the shorter arc."""
    return Transform2D(
        a.x + (b.x - a.x) * fraction,
        a.y + (b.y - a.y) * fraction,
        normalize_angle(a.yaw + normalize_angle(b.yaw - a.yaw) * fraction),
    )


@dataclass(frozen=True)
class MapCorrection:
    """map -> odom moved between two stamps: the robot's pose in the map moved by `distance`
    metres and `yaw` radians without the robot moving (SLAM relocalized)."""

    since: float
    stamp: float
    distance: float
    yaw: float
    before: Transform2D
    after: Transform2D


class _History:
    """One dynamic edge: samples sorted by stamp, at most `keep` seconds behind the newest."""

    def __init__(self, keep: float) -> None:
        self.keep = keep
        self.stamps: list[float] = []
        self.values: list[Transform2D] = []

    def add(self, stamp: float, value: Transform2D) -> None:
        i = bisect.bisect_left(self.stamps, stamp)
        if i < len(self.stamps) and self.stamps[i] == stamp:
            self.values[i] = value  # a re-sent sample replaces the one it repeats
        else:
            self.stamps.insert(i, stamp)
            self.values.insert(i, value)
        cut = bisect.bisect_left(self.stamps, self.stamps[-1] - self.keep)
        del self.stamps[:cut], self.values[:cut]

    def at(self, stamp: float | None, edge: str) -> Transform2D:
        if stamp is None:
            return self.values[-1]
        first, last = self.stamps[0], self.stamps[-1]
        if not first <= stamp <= last:
            raise TransformUnavailable(
                f"{edge} is not known at {stamp:.3f} s: the history kept holds {first:.3f} s "
                f"to {last:.3f} s (ask within it, or for the latest)"
            )
        i = bisect.bisect_left(self.stamps, stamp)
        if self.stamps[i] == stamp:
            return self.values[i]
        t0, t1 = self.stamps[i - 1], self.stamps[i]
        return interpolate(self.values[i - 1], self.values[i], (stamp - t0) / (t1 - t0))

    def latest_at_or_before(self, stamp: float) -> tuple[float, Transform2D]:
        i = max(bisect.bisect_right(self.stamps, stamp) - 1, 0)
        return self.stamps[i], self.values[i]


class TfTree:
    """A tree of 2-D frames: each child has one parent, through a static transform or a
    history of stamped ones. Not thread-safe: one owner feeds and asks it (a ROS callback group
    or a lock around it)."""

    def __init__(
        self,
        *,
        keep: float = 10.0,
        jump_distance: float = 0.2,
        jump_yaw: float = math.radians(10.0),
        ahead: float = STAMP_AHEAD,
    ) -> None:
        """`keep`: seconds of history per dynamic edge (and the oldest stamp taken, behind the
        clock); `ahead`: seconds a stamp may be ahead of the clock; `jump_distance` (metres) and
        `jump_yaw` (radians): the smallest map -> odom correction `map_to_odom_jump` reports."""
        self.keep = keep
        self.stamps = StampWindow(ahead=ahead, behind=keep)
        self.jump_distance = jump_distance
        self.jump_yaw = jump_yaw
        self._parent: dict[str, str] = {}
        self._static: dict[str, Transform2D] = {}
        self._dynamic: dict[str, _History] = {}

    # -- feeding ---------------------------------------------------------------------------

    def set_static(self, parent: str, child: str, transform: Transform2D) -> None:
        """`child` sits at `transform` in `parent`, at every time (/tf_static)."""
        self._link(parent, child, transform)
        self._dynamic.pop(child, None)
        self._static[child] = transform

    def set_transform(
        self, parent: str, child: str, stamp: float, transform: Transform2D, *, now: float
    ) -> None:
        """`child` sits at `transform` in `parent` at `stamp` (/tf), received at `now` (the
        same clock). Raises TransformUnavailable, keeping nothing of it, for a stamp outside
        the window around `now`, a transform that is not finite, or a frame with two parents."""
        problem = self.stamps.problem(stamp, now)
        if problem is not None:
            raise TransformUnavailable(f"{parent} -> {child} {problem}; not kept")
        self._link(parent, child, transform)
        self._static.pop(child, None)
        self._dynamic.setdefault(child, _History(self.keep)).add(stamp, transform)

    def set_map_to_odom(self, stamp: float, transform: Transform2D, *, now: float) -> None:
        self.set_transform(MAP, ODOM, stamp, transform, now=now)

    def set_odom_to_base(self, stamp: float, transform: Transform2D, *, now: float) -> None:
        self.set_transform(ODOM, BASE, stamp, transform, now=now)

    def _link(self, parent: str, child: str, transform: Transform2D) -> None:
        bad = not_finite(x=transform.x, y=transform.y, yaw=transform.yaw)
        if bad:
            raise TransformUnavailable(f"{parent} -> {child} is not finite ({bad}); not kept")
        if self._parent.get(child, parent) != parent:
            raise TransformUnavailable(
                f"{child} already has the parent {self._parent[child]}, not {parent}: a frame has "
                "one parent (two publishers of its transform?)"
            )
        frame: str | None = parent
        while frame is not None:
            if frame == child:
                raise TransformUnavailable(f"{parent} -> {child} would make a loop of frames")
            frame = self._parent.get(frame)
        self._parent[child] = parent

    # -- asking ----------------------------------------------------------------------------

    def frames(self) -> set[str]:
        return set(self._parent) | set(self._parent.values())

    def lookup(self, target: str, source: str, stamp: float | None = None) -> Transform2D:
        """The transform taking coordinates in `source` into `target` at `stamp` (None: each
        edge's latest). Raises TransformUnavailable for an unknown frame, frames in two trees,
        or a stamp outside a history on the way."""
        for frame in (target, source):
            if frame not in self.frames():
                known = ", ".join(sorted(self.frames())) or "none yet"
                raise TransformUnavailable(f"no frame '{frame}' (frames known: {known})")
        to_target, root_t = self._to_root(target, stamp)
        to_source, root_s = self._to_root(source, stamp)
        if root_t != root_s:
            raise TransformUnavailable(
                f"'{target}' and '{source}' are in two trees (roots {root_t} and {root_s}): "
                "a transform between them has not been published"
            )
        return to_target.inverse().compose(to_source)

    def _to_root(self, frame: str, stamp: float | None) -> tuple[Transform2D, str]:
        """root<-frame, and the root's name."""
        out = Transform2D()
        while frame in self._parent:
            parent = self._parent[frame]
            history = self._dynamic.get(frame)
            edge = history.at(stamp, f"{parent} -> {frame}") if history else self._static[frame]
            out = edge.compose(out)
            frame = parent
        return out, frame

    def to_odom(self, pose: Pose2D, stamp: float | None = None) -> Pose2D:
        """`pose` in the map, in odom."""
        return self.lookup(ODOM, MAP, stamp).apply(pose)

    def to_map(self, pose: Pose2D, stamp: float | None = None) -> Pose2D:
        """`pose` in odom, in the map."""
        return self.lookup(MAP, ODOM, stamp).apply(pose)

    def map_to_odom_jump(self, since: float) -> MapCorrection | None:
        """The map -> odom correction since `since` (the sample in force then; the oldest kept
        if `since` is older), measured where it matters: how far it moved the robot's pose in
        the map (at the latest odom -> base_link; odom's origin without one). None when it moved
        less than both thresholds, or no map -> odom is known."""
        history = self._dynamic.get(ODOM) if self._parent.get(ODOM) == MAP else None
        if history is None:
            return None
        then, before = history.latest_at_or_before(since)
        stamp, after = history.stamps[-1], history.values[-1]
        base = self._dynamic.get(BASE) if self._parent.get(BASE) == ODOM else None
        robot = base.values[-1] if base else Transform2D()
        was, now = before.compose(robot), after.compose(robot)
        distance = math.hypot(now.x - was.x, now.y - was.y)
        yaw = normalize_angle(now.yaw - was.yaw)
        if distance <= self.jump_distance and abs(yaw) <= self.jump_yaw:
            return None
        return MapCorrection(then, stamp, distance, yaw, before, after)
