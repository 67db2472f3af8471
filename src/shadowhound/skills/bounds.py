"""Bounds a running step keeps whatever odometry says.

The plan check proves the planned path safe; the closed loop then steers on the measured pose.
When odometry lies while it still arrives (a relocalization jump, a frozen stream, a second
source), a loop that believes it walks on, in truth past what was allowed. So each step also
keeps bounds from what it *commanded*, which no sensor can corrupt:

- `CommandLedger`: the step's velocity commands dead-reckoned from the pose it started at:
  where the robot is if it did what it was told, how far and how much it was told to turn;
- a leg's commanded travel, and a turn's commanded angle, may exceed the planned leg by
  `safety.step_travel_margin` plus `safety.step_travel_slack` of its length, no more;
- `room_ahead`: how far the robot may go along a heading before its body would reach a
  geofence, judged from the commanded pose and from the measured pose (the stricter wins);
- `room_on_map`: how far before its body would touch anything on the map, the rule a mission's
  legs are checked by (`world.check_leg`); motion whose path is not known before it runs
  (nav.follow, teleoperation) looks along its heading with it every tick, and `brake_speed`
  is the fastest speed that still stops within the room.

The motion loops (motion.py) brake within the smallest of these, as they brake for the goal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import geofence
from ..config import SafetyConfig
from ..state import Pose2D
from ..world import Belief, check_leg

STOP_SHORT = 0.05  # metres kept short of a fence or an obstacle when braking for it


def fences(lim: SafetyConfig) -> list[tuple[geofence.Fence, str, str]]:
    """Every geofence of the limits: (fence, its name, where it is configured)."""
    found: list[tuple[geofence.Fence, str, str]] = [
        (
            geofence.CircleFence(lim.geofence_radius),
            f"the geofence of {lim.geofence_radius:g} m",
            "around the origin (safety.geofence_radius)",
        )
    ]
    if lim.geofence_polygon:
        found.append(
            (
                geofence.PolygonFence(lim.geofence_polygon),
                "the geofence polygon",
                "(safety.geofence_polygon)",
            )
        )
    return found


def room_ahead(
    lim: SafetyConfig, at: Pose2D, heading: float, reach: float, slack: float = 0.0
) -> tuple[float, str]:
    """Metres the robot's centre may go from `at` along `heading` (looking `reach` ahead)
    before its body would reach a fence (less `slack`: control tolerance), and the fence's
    name. A centre already within the body's margin may not come closer than it is (the rule
    `geofence.leg_breach` applies)."""
    a = (at.x, at.y)
    b = (at.x + reach * math.cos(heading), at.y + reach * math.sin(heading))
    room, name = reach, ""
    for fence, fence_name, _where in fences(lim):
        need = max(0.0, min(lim.geofence_margin, fence.clearance(a)) - slack)
        t = fence.first_below(a, b, need)
        if t is not None and t * reach < room:
            room, name = t * reach, fence_name
    return room, name


def room_on_map(
    belief: Belief | None, at: Pose2D, heading: float, reach: float
) -> tuple[float, str]:
    """Metres the robot's centre may go from `at` along `heading` (looking `reach` ahead)
    before its body would touch what is on the map, and what that is ("the blue box", "the
    wall", "unmapped space"): what is in the way of a mission's leg (`world.check_leg`, its
    rule for a body already near something included) is in the way here. (reach, "") with no
    map, or nothing in the way."""
    if belief is None:
        return reach, ""
    end = (at.x + reach * math.cos(heading), at.y + reach * math.sin(heading))
    leg = check_leg(belief, (at.x, at.y), end)
    return (reach, "") if leg.clear else (leg.distance, leg.obstacle)


def room_along(
    lim: SafetyConfig, belief: Belief | None, at: Pose2D, heading: float, reach: float
) -> tuple[float, str]:
    """The smaller of `room_ahead` (the geofences) and `room_on_map` (anything on the map)
    from `at` along `heading`, and what limits it ("" when nothing within `reach`)."""
    room, why = room_ahead(lim, at, heading, reach)
    ahead, what = room_on_map(belief, at, heading, reach)
    return (ahead, what) if what and ahead < room else (room, why)


def brake_speed(room: float, accel: float, period: float) -> float:
    """The fastest speed that, held for one control `period` and then braked at `accel`,
    stops within `room` metres: v * period + v^2 / (2 accel) = room."""
    room = max(0.0, room)
    return max(0.0, -accel * period + math.sqrt((accel * period) ** 2 + 2 * accel * room))


@dataclass
class CommandLedger:
    """A step's velocity commands, dead-reckoned from where it started (robot clock)."""

    pose: Pose2D  # where the commands alone put the robot, as of `t` (yaw unwrapped)
    t: float
    travelled: float = 0.0  # metres commanded (path length)
    turned: float = 0.0  # radians commanded (absolute)
    command: tuple[float, float, float] = (0.0, 0.0, 0.0)
    anchor: Pose2D | None = None  # where the current leg began (measured)

    def __post_init__(self) -> None:
        if self.anchor is None:
            self.anchor = self.pose

    def begin_leg(self, t: float, at: Pose2D) -> None:
        """A leg starts at `at` (measured, at rest): commanded poses count from there."""
        self.advance(t)
        self.pose = self.anchor = at

    def offset(self, t: float) -> tuple[float, float, float]:
        """Where the commands took the robot from the leg's start: metres along x and y (odom
        frame) and radians turned (signed), as of t."""
        self.advance(t)
        a = self.anchor or self.pose
        return self.pose.x - a.x, self.pose.y - a.y, self.pose.yaw - a.yaw

    def advance(self, t: float) -> None:
        """Hold the current command until t (the robot clock's now)."""
        dt = t - self.t
        if dt <= 0:
            return
        vx, vy, wz = self.command
        mid = self.pose.yaw + wz * dt / 2
        c, s = math.cos(mid), math.sin(mid)
        self.pose = Pose2D(
            self.pose.x + (vx * c - vy * s) * dt,
            self.pose.y + (vx * s + vy * c) * dt,
            self.pose.yaw + wz * dt,  # unwrapped: turns add up
        )
        self.travelled += math.hypot(vx, vy) * dt
        self.turned += abs(wz) * dt
        self.t = t

    def set(self, t: float, vx: float, vy: float, wz: float) -> float:
        """A new command from time t; returns the metres commanded since the last one."""
        before = self.travelled
        self.advance(t)
        self.command = (vx, vy, wz)
        return self.travelled - before


def leg_margin(lim: SafetyConfig, metres: float) -> float:
    """Metres a step's commands may take the robot off a planned straight leg of `metres`
    (beyond its end, behind its start or to its side)."""
    return abs(metres) * lim.step_travel_slack + lim.step_travel_margin


def turn_margin(lim: SafetyConfig, radians: float) -> float:
    """Radians a step's commands may turn beyond a planned turn of `radians` (or back)."""
    return abs(radians) * lim.step_travel_slack + math.radians(lim.step_turn_margin_deg)


def leg_room(
    at: tuple[float, float], heading: float, goal: tuple[float, float], margin: float
) -> float:
    """Metres the commands may still take the robot from `at` along `heading` and keep it
    within `margin` of the planned leg, the segment from (0, 0) (where the leg began) to
    `goal`: the capsule around it. 0 when `at` is already outside and `heading` does not
    lead back in."""
    dx, dy = math.cos(heading), math.sin(heading)

    def off(s: float) -> float:  # distance from the leg of the point s metres ahead
        return _to_segment((at[0] + s * dx, at[1] + s * dy), goal) - margin

    if off(0.0) > 0:
        return 0.0 if off(1e-3) >= off(0.0) else 1e-3  # outside: only a way back may go on
    # The distance to a segment is convex along a line: one crossing out, found by halving.
    reach = math.hypot(*goal) + 2 * margin + math.hypot(*at)
    if off(reach) <= 0:
        return reach
    low, high = 0.0, reach
    for _ in range(40):
        mid = (low + high) / 2
        low, high = (mid, high) if off(mid) <= 0 else (low, mid)
    return low


def turn_room(turned: float, direction: float, planned: float, margin: float) -> float:
    """Radians the commands may still turn toward `direction` (its sign) from `turned` (signed,
    from where the turn began) and stay within `margin` of the planned turn (0 to `planned`)."""
    if direction >= 0:
        return max(0.0, max(0.0, planned) + margin - turned)
    return max(0.0, turned - min(0.0, planned) + margin)


def _to_segment(p: tuple[float, float], b: tuple[float, float]) -> float:
    """Distance from p to the segment from the origin to b."""
    length2 = b[0] * b[0] + b[1] * b[1]
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, (p[0] * b[0] + p[1] * b[1]) / length2))
    return math.hypot(p[0] - t * b[0], p[1] - t * b[1])
