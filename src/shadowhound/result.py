"""What a mission produced: per-step outcomes, timing, usage and the robot state after."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, Protocol

from .jsonout import number
from .plan import Plan, Usage
from .state import Pose2D, RobotState


class SkillFacts(Protocol):
    """What reports and memory read of a skill (skills.registry.Skill declares it)."""

    @property
    def reports(self) -> bool: ...

    @property
    def remembered_as(self) -> str | None: ...


class SkillBook(Protocol):
    """Where skills are looked up by name (skills.registry.SkillRegistry)."""

    def find(self, name: str) -> SkillFacts | None: ...


class StepStatus(str, Enum):
    PENDING = "pending"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"
    SKIPPED = "skipped"


class MissionStatus(str, Enum):
    """Agent status, also reported by diagnostics."""

    IDLE = "idle"
    PLANNING = "planning"
    EXECUTING = "executing"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    STOPPED = "stopped"


@dataclass
class StepResult:
    """One step of a mission. Durations: wall seconds, and seconds on the robot's clock."""

    index: int
    skill: str
    args: dict[str, Any]
    label: str = ""
    status: StepStatus = StepStatus.PENDING
    started_at: float | None = None  # wall-clock epoch seconds
    duration: float = 0.0
    robot_duration: float = 0.0
    output: str = ""
    error: str | None = None
    # The conditions watched while it runs (plan.Watch.to_dict each); none for most steps.
    watches: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        out = {
            "index": self.index,
            "skill": self.skill,
            "args": self.args,
            "label": self.label,
            "status": self.status.value,
            "started_at": self.started_at,
            "duration": round(self.duration, 6),
            "robot_duration": number(self.robot_duration, 3),  # the robot's clock
            "output": self.output,
            "error": self.error,
        }
        if self.watches:
            out["watches"] = self.watches
        return out

    def watching(self) -> str:
        """The conditions in the person's words: "until you see the red ball" ("")."""
        return "; ".join(str(w.get("words") or w.get("kind", "")) for w in self.watches)


@dataclass
class Timing:
    """Where the time of a mission went (wall seconds). Keys match the original ShadowHound."""

    agent_duration: float = 0.0  # planning
    execution_duration: float = 0.0  # inside skills
    total_duration: float = 0.0
    robot_duration: float = 0.0  # robot-clock seconds the steps took

    @property
    def overhead_duration(self) -> float:
        return max(0.0, self.total_duration - self.agent_duration - self.execution_duration)

    @property
    def agent_percentage(self) -> float:
        return 100.0 * self.agent_duration / self.total_duration if self.total_duration else 0.0

    def to_dict(self) -> dict[str, float | None]:
        return {
            "agent_duration": round(self.agent_duration, 6),
            "execution_duration": round(self.execution_duration, 6),
            "overhead_duration": round(self.overhead_duration, 6),
            "total_duration": round(self.total_duration, 6),
            "agent_percentage": round(self.agent_percentage, 2),
            "robot_duration": number(self.robot_duration, 3),
        }


@dataclass
class MissionResult:
    """The outcome of `execute_mission`. Unpacks as `(response, timing)` for old callers."""

    mission_id: str
    mission: str
    success: bool
    response: str
    status: MissionStatus
    steps: list[StepResult] = field(default_factory=list)
    robot: RobotState | None = None
    timing: Timing = field(default_factory=Timing)
    usage: Usage = field(default_factory=Usage)
    plan: Plan | None = None
    refusals: list[str] = field(default_factory=list)
    error: str | None = None
    dry_run: bool = False
    predicted_path: list[Pose2D] = field(default_factory=list)  # dry runs: poses, start first
    planner: str = ""  # the planning configured: offline | llm | hybrid (see plan.planned_by)

    def __iter__(self) -> Iterator[Any]:
        yield self.response
        yield self.timing.to_dict()

    def to_dict(self) -> dict[str, Any]:
        return {
            "mission_id": self.mission_id,
            "mission": self.mission,
            "success": self.success,
            "status": self.status.value,
            "response": self.response,
            "error": self.error,
            "refusals": list(self.refusals),
            "dry_run": self.dry_run,
            "planner": self.planner,
            "planned_by": self.plan.planned_by if self.plan else "",
            "predicted_path": [
                {"x": number(p.x, 4), "y": number(p.y, 4), "yaw": number(p.yaw, 4)}
                for p in self.predicted_path
            ],
            "plan": self.plan.to_dict() if self.plan else None,
            "steps": [s.to_dict() for s in self.steps],
            "robot": self.robot.to_dict() if self.robot else None,
            "timing": self.timing.to_dict(),
            "usage": self.usage.to_dict(),
        }

    def history_row(self) -> dict[str, Any]:
        """The row a history listing shows (the database's shape; no times in memory)."""
        return {
            "id": self.mission_id,
            "mission": self.mission,
            "status": self.status.value,
            "success": self.success,
            "response": self.response,
            "started_at": None,
            "finished_at": None,
        }

    def summary(self) -> str:
        return f"{self.status.value}: {self.mission!r} -> {self.response}"


def compose_response(
    status: MissionStatus, steps: list[StepResult], plan: Plan, error: str | None, skills: SkillBook
) -> str:
    """The sentence a person reads: what was done and, for reports, the answers themselves
    (the output of a skill of `skills` that declares `reports`)."""
    done = [s.output for s in steps if s.status is StepStatus.SUCCEEDED and s.output]
    if status is MissionStatus.SUCCEEDED:
        reports = [s.output for s in steps if _reports(skills, s.skill)]
        actions = [s.output for s in steps if not _reports(skills, s.skill) and s.output]
        parts = ["Done: " + "; ".join(actions) + "."] if actions else []
        parts += [o[0].upper() + o[1:] + ("" if o.endswith(".") else ".") for o in reports]
        if plan.notes:
            parts.append("(" + "; ".join(plan.notes) + ")")
        return " ".join(parts)
    failed = next((s for s in steps if s.status in (StepStatus.FAILED, StepStatus.CANCELLED)), None)
    where = f" at step {failed.index} ({failed.skill})" if failed else ""
    verb = "Stopped" if status is MissionStatus.STOPPED else "Failed"
    text = f"{verb}{where}: {error}."
    if done:
        text += " Completed before that: " + "; ".join(done) + "."
    return text + " The robot is stopped."


def _reports(skills: SkillBook, name: str) -> bool:
    skill = skills.find(name)
    return skill is not None and skill.reports
