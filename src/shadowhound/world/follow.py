"""A path follower: one velocity command per control tick that walks a planned path's legs and
ends facing a goal heading. The controller of `shadowhound sim-driver`'s navigate_to_pose
server (the project's own stand-in for Nav2's controller server).

Turn in place towards the next waypoint when it lies more than `turn_first` off the heading,
else walk at it with a proportional heading correction, slowing down over the last `brake`
metres; a waypoint counts as passed within `pass_radius`; at the goal (within `tolerance`),
turn to the goal heading.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..state import Pose2D, normalize_angle


@dataclass
class PathFollower:
    """Follows `points` (odom frame; the goal last) and ends facing `yaw`."""

    points: list[tuple[float, float]]
    yaw: float
    speed: float = 0.4  # m/s
    turn_rate: float = 0.8  # rad/s
    tolerance: float = 0.03  # metres from the goal that count as there
    yaw_tolerance: float = 0.03  # radians
    pass_radius: float = 0.15  # metres from an intermediate waypoint that count as passed
    turn_first: float = 0.5  # radians off the leg beyond which the robot turns in place
    brake: float = 0.5  # metres over which the speed falls to zero at the goal
    _next: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        if not self.points:
            raise ValueError("a path needs at least its goal")

    def remaining(self, pose: Pose2D) -> float:
        """Metres left along the path from `pose`."""
        here, total = (pose.x, pose.y), 0.0
        for point in self.points[self._next :]:
            total += math.dist(here, point)
            here = point
        return total

    def command(self, pose: Pose2D) -> tuple[float, float, float] | None:
        """Body-frame (vx, vy, wz) for this tick, or None when the goal pose is reached."""
        last = len(self.points) - 1
        while (
            self._next < last
            and math.dist((pose.x, pose.y), self.points[self._next]) <= self.pass_radius
        ):
            self._next += 1
        tx, ty = self.points[self._next]
        distance = math.hypot(tx - pose.x, ty - pose.y)
        at_goal = self._next == last and distance <= self.tolerance
        if at_goal:
            error = normalize_angle(self.yaw - pose.yaw)
            if abs(error) <= self.yaw_tolerance:
                return None
            return (0.0, 0.0, self._turn(error))
        error = normalize_angle(math.atan2(ty - pose.y, tx - pose.x) - pose.yaw)
        if abs(error) > self.turn_first:
            return (0.0, 0.0, self._turn(error))
        left = self.remaining(pose)
        vx = self.speed * min(1.0, max(0.1, left / self.brake)) * math.cos(error)
        vx = min(vx, left * 2.0)  # never more than half a second from the goal per tick
        return (vx, 0.0, self._turn(error))

    def _turn(self, error: float) -> float:
        wz = max(-self.turn_rate, min(self.turn_rate, 2.0 * error))
        if abs(wz) < 0.1:  # the Go2 rounds Moves to 0.01; keep a turn that still turns
            wz = math.copysign(0.1, error) if abs(error) > self.yaw_tolerance / 2 else 0.0
        return wz
