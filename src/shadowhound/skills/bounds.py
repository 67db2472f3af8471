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

The commands are dead-reckoned from when they were sent; a robot acts on each once it has it.
A command held up on the way (a loaded machine stalls this process, the link or the driver)
acts late by as much, so an honest robot ends up to (each change of speed) x (how long a stall
seen around it may have held it up) from where its commands put it: further along when a
slowing came late, short when a speed-up did. `CommandLedger.leeway` says how far; a change of
speed that no stall seen could have held up counts for nothing, so with no stall seen it is
zero and the checks are exactly as strict as the margins say.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from .. import geofence
from ..config import SafetyConfig
from ..robot.base import MAX_STALL, Stall
from ..state import Pose2D
from ..world import Belief, check_leg

STOP_SHORT = 0.05  # metres kept short of a fence or an obstacle when braking for it

# Seconds a stop (StopMove) may wait for the driver's request loop before it acts (go2_ros2_sdk
# runs it at 10 Hz): a stall that begins that soon after a change holds it up too.
STOP_LOOP = 0.1

__all__ = [
    "MAX_STALL",
    "STOP_LOOP",
    "CommandLedger",
    "Leeway",
    "fences",
    "leg_margin",
    "leg_room",
    "room_ahead",
    "turn_margin",
    "turn_room",
]


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


@dataclass(frozen=True)
class Leeway:
    """How far an honest robot may be, at rest, from where its leg's commands put it: along
    the leg (or turn) beyond them and short of them, and to either side (metres or radians)."""

    ahead: float = 0.0
    behind: float = 0.0
    aside: float = 0.0

    def catch_up(self, lag: float, margin: float) -> float:
        """How much further the commands may go for a robot odometry shows `lag` behind them:
        as far as it lags, at most `behind`; nothing when it lags by more than the stalls seen
        and the `margin` explain (a lie, or a robot that does not follow)."""
        return min(lag, self.behind) if 0.0 < lag <= self.behind + margin else 0.0


@dataclass
class CommandLedger:
    """A step's velocity commands, dead-reckoned from where it started (robot clock)."""

    pose: Pose2D  # where the commands alone put the robot, as of `t` (yaw unwrapped)
    t: float
    travelled: float = 0.0  # metres commanded (path length)
    turned: float = 0.0  # radians commanded (absolute)
    command: tuple[float, float, float] = (0.0, 0.0, 0.0)
    anchor: Pose2D | None = None  # where the current leg began (measured)
    # The leg's changes of commanded velocity (when, and by how much: odom frame vx, vy, wz).
    changes: list[tuple[float, float, float, float]] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.anchor is None:
            self.anchor = self.pose

    def begin_leg(self, t: float, at: Pose2D) -> None:
        """A leg starts at `at` (measured, at rest): commanded poses count from there."""
        self.advance(t)
        self.pose = self.anchor = at
        self.changes.clear()

    def leeway(
        self, stalls: Sequence[Stall], axis: tuple[float, float, float], accel: float
    ) -> Leeway:
        """How far an honest robot may be from the leg's commands when each change of them
        may have acted as late as a stall seen around it held it up (in order; at most
        MAX_STALL): each slowing along `axis` (a unit vector: the leg's direction in the odom
        frame and 0, or (0, 0, +-1) for a turn) lets it go on further, each speed-up leaves it
        short, each change across it off to a side. The changes a stall held act together
        when it ends, so the robot then takes its acceleration limit (`accel`) to follow them
        all, as far again as a change of that size sent at once."""
        ahead = behind = aside = 0.0
        held_by: dict[int, list[float]] = {}  # per stall: the slowings, the speed-ups it held
        ux, uy, uw = axis
        for t, dx, dy, dw in self.changes:
            around = [
                (s.end - t, i) for i, s in enumerate(stalls) if s.start - STOP_LOOP < t < s.end
            ]
            if not around:
                continue
            late, which = max(around)
            held = min(MAX_STALL, late)
            along = dx * ux + dy * uy + dw * uw
            ahead, behind = ahead + held * max(0.0, -along), behind + held * max(0.0, along)
            aside += held * abs(dy * ux - dx * uy)
            sums = held_by.setdefault(which, [0.0, 0.0])
            sums[0], sums[1] = sums[0] + max(0.0, -along), sums[1] + max(0.0, along)
        for slowed, sped in held_by.values():
            ahead, behind = ahead + slowed**2 / (2 * accel), behind + sped**2 / (2 * accel)
        return Leeway(ahead, behind, aside)

    def halt(self, t: float, linear_accel: float, angular_accel: float) -> float:
        """A stop sent at once from full speed, outside the loop's ramps: the robot brakes at
        its acceleration limits, going on as far as that takes it. Returns the metres
        commanded since the last command."""
        moving = any(self.command)
        walked = self.set(t, 0.0, 0.0, 0.0)
        vx, vy, wz = self.changes[-1][1:] if moving else (0.0, 0.0, 0.0)  # less what it was
        speed = math.hypot(vx, vy)
        brake = speed / (2 * linear_accel)  # metres per m/s: v^2 / 2a
        turn = abs(wz) / (2 * angular_accel)
        self.pose = Pose2D(
            self.pose.x - vx * brake, self.pose.y - vy * brake, self.pose.yaw - wz * turn
        )
        self.travelled += speed * brake
        self.turned += abs(wz) * turn
        return walked + speed * brake

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
        if (vx, vy, wz) != self.command:
            c, s = math.cos(self.pose.yaw), math.sin(self.pose.yaw)
            (ox, oy, ow), (nx, ny) = self.command, (vx * c - vy * s, vx * s + vy * c)
            self.changes.append((t, nx - (ox * c - oy * s), ny - (ox * s + oy * c), wz - ow))
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
    `goal`: the capsule around it. From outside it (a stalled control loop held a command
    too long), only a way back: as far as it comes no further from the leg than it is, or
    once back in, to the capsule's edge; 0 when `heading` does not lead back."""
    dx, dy = math.cos(heading), math.sin(heading)

    def off(s: float) -> float:  # distance from the leg of the point s metres ahead
        return _to_segment((at[0] + s * dx, at[1] + s * dy), goal) - margin

    # The distance to a segment is convex along a line: one stretch inside, found by halving.
    reach = math.hypot(*goal) + 2 * margin + math.hypot(*at)
    low = 0.0
    if off(0.0) > 0:
        if off(1e-3) >= off(0.0):
            return 0.0
        high = reach  # the nearest point along the line, by thirds
        for _ in range(60):
            a, b = low + (high - low) / 3, high - (high - low) / 3
            low, high = (low, b) if off(a) <= off(b) else (a, high)
        if off(low) > 0:
            return low  # it never comes back in: as near as it gets
    if off(reach) <= 0:
        return reach
    high = reach
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
