"""The mission budget: what one mission has used so far of the limits that bind it as a whole.

The agent makes one `MissionBudget` when a mission starts and keeps it in the mission's
`PlanEnv`, so every check of that mission reads the same budget: the first plan, a re-plan
after a failed step, each react step, and the re-check just before a step runs. Without it each
batch of steps would be checked as if the mission had just begun.

What it counts is measured, not predicted: the distance is the robot's own odometer since the
mission started (a detour or a half-finished step counts as walked) or, when larger, the
distance its steps commanded (odometry can lie; commands cannot), the time is the robot's
clock since then, and the approvals are the exact calls a person approved.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from .state import RobotState


@dataclass
class MissionBudget:
    """Readings at the mission's start, the robot's clock, and the calls a person approved."""

    odometer_start: float  # RobotState.distance_travelled when the mission started
    clock_start: float  # robot clock (Robot.now) when the mission started
    clock: Callable[[], float]  # the robot's clock
    _approved: list[object] = field(default_factory=list)
    commanded: float = 0.0  # metres the mission's steps commanded (SkillContext.drive)

    @classmethod
    def start(cls, state: RobotState, clock: Callable[[], float]) -> MissionBudget:
        odometer = state.distance_travelled
        return cls(odometer if math.isfinite(odometer) else math.nan, clock(), clock)

    def command(self, metres: float) -> None:
        """Count metres a step commanded (dead-reckoned from its velocity commands)."""
        if math.isfinite(metres) and metres > 0:
            self.commanded += metres

    def travelled(self, state: RobotState) -> float:
        """Metres the robot walked since the mission started: the larger of what odometry
        measured and what the steps commanded (odometry may lie; a step cannot walk less than
        it was told and still count less). Always finite."""
        measured = state.distance_travelled - self.odometer_start
        if not math.isfinite(measured):
            measured = 0.0  # the odometer cannot say: what was commanded still counts
        return max(0.0, measured, self.commanded)

    def elapsed(self) -> float:
        """Seconds on the robot's clock since the mission started (planning and waits too)."""
        return max(0.0, self.clock() - self.clock_start)

    def deadline(self, limit: float) -> float:
        """The robot-clock time at which a mission allowed `limit` seconds must have ended."""
        return self.clock_start + limit

    def grant(self, calls: Iterable[object]) -> None:
        """Record calls a person approved. Only these very objects count as approved: an
        approval is for the step that was shown, not for every later step that looks alike."""
        self._approved.extend(calls)

    def granted(self, call: object) -> bool:
        return any(c is call for c in self._approved)


def walked_too_far(walked: float, limit: float) -> str:
    """Why a step stopped when the robot measurably walked past the mission's distance."""
    return (
        f"the robot has walked {walked:.2f} m in this mission, past the limit of {limit:g} m "
        "(safety.max_mission_distance)"
    )


def out_of_time(limit: float) -> str:
    """Why a step stopped or was refused when the mission's time ran out."""
    return (
        f"the mission's time is up: it may take {limit:g} s on the robot's clock "
        "(safety.max_mission_duration)"
    )
