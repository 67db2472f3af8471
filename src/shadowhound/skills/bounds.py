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
  geofence, judged from the commanded pose and from the measured pose (the stricter wins).

The motion loops (motion.py) brake within the smallest of these, as they brake for the goal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import geofence
from ..config import SafetyConfig
from ..state import Pose2D


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


def leg_allowance(lim: SafetyConfig, metres: float) -> float:
    """Metres from its start a step may command for a planned straight leg of `metres`."""
    return abs(metres) * (1.0 + lim.step_travel_slack) + lim.step_travel_margin


def turn_allowance(lim: SafetyConfig, radians: float) -> float:
    """Radians from its start a step may command for a planned turn of `radians`."""
    return abs(radians) * (1.0 + lim.step_travel_slack) + math.radians(lim.step_turn_margin_deg)


def leg_room(offset: tuple[float, float], heading: float, allowed: float) -> float:
    """Metres the commands may still take the robot along `heading` from `offset` (from the
    leg's start) and stay within `allowed` of the start: back toward it, more than ahead."""
    ox, oy = offset
    dx, dy = math.cos(heading), math.sin(heading)
    along = ox * dx + oy * dy
    rest = allowed * allowed - (ox * ox + oy * oy)
    return max(0.0, -along + math.sqrt(max(0.0, along * along + rest)))


def turn_room(turned: float, direction: float, allowed: float) -> float:
    """Radians the commands may still turn toward `direction` (its sign) from `turned` (signed,
    from the leg's start) and stay within `allowed` of the start."""
    return max(0.0, allowed - math.copysign(1.0, direction) * turned)
