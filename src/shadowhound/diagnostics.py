"""What the agent is doing, for people and monitors: the live mission progress and a typed
snapshot of it.

`MissionTracker` is written by the running mission and read from any thread (a dashboard
polls it while the mission runs). `Diagnostics` is one consistent snapshot; `to_dict()` is its
JSON form, made only at the edges (the Python API's `get_diagnostics`, the web API); the ROS
node turns the same object into DiagnosticStatus key-values (ros/convert.py).
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from .jsonout import number
from .result import MissionStatus

if TYPE_CHECKING:
    from .approval import ApprovalRequest
    from .config import SafetyConfig
    from .state import RobotState


@dataclass(frozen=True)
class Progress:
    """The mission now: which one, which step of how many, and how far along (0..1)."""

    status: MissionStatus = MissionStatus.IDLE
    mission_id: str | None = None
    mission: str | None = None
    skill: str | None = None
    step: int = 0
    steps: int = 0
    progress: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """The mission's progress as the web status and diagnostics report it."""
        return {
            "status": self.status.value,
            "mission_id": self.mission_id,
            "mission": self.mission,
            "current_skill": self.skill,
            "step": self.step,
            "steps": self.steps,
            "progress": number(self.progress, 3),
        }


class MissionTracker:
    """Thread-safe progress and the last errors (the same error twice in a row is kept once)."""

    def __init__(self, max_errors: int = 20) -> None:
        self._lock = threading.Lock()
        self._now = Progress()
        self._errors: deque[str] = deque(maxlen=max_errors)

    def start(self, mission_id: str, mission: str) -> None:
        with self._lock:
            self._now = Progress(MissionStatus.PLANNING, mission_id, mission)

    def set_status(self, status: MissionStatus) -> None:
        self._update(status=status)

    def step_started(self, skill: str, step: int) -> None:
        self._update(skill=skill, step=step)

    def set_steps(self, steps: int) -> None:
        self._update(steps=steps)

    def at_least_steps(self, steps: int) -> None:
        with self._lock:
            self._now = replace(self._now, steps=max(self._now.steps, steps))

    def step_progress(self, index: int, fraction: float) -> None:
        """Step `index` (1-based) is `fraction` done."""
        with self._lock:
            total = self._now.steps or 1
            self._now = replace(self._now, progress=min(1.0, ((index - 1) + fraction) / total))

    def finished(self, status: MissionStatus) -> None:
        with self._lock:
            done = 1.0 if status is MissionStatus.SUCCEEDED else self._now.progress
            self._now = replace(self._now, status=status, skill=None, progress=done)

    def note_error(self, text: str) -> None:
        with self._lock:
            if not self._errors or self._errors[-1] != text:
                self._errors.append(text)

    def snapshot(self) -> tuple[Progress, list[str]]:
        with self._lock:
            return self._now, list(self._errors)

    @property
    def mission_id(self) -> str:
        with self._lock:
            return self._now.mission_id or ""

    def _update(self, **values: Any) -> None:
        with self._lock:
            self._now = replace(self._now, **values)


@dataclass(frozen=True)
class Diagnostics:
    """One snapshot of the agent. `robot` is None with `robot_error` saying why when the robot
    cannot report its state."""

    progress: Progress
    errors: list[str]
    estop: bool
    backend: str
    robot: RobotState | None
    robot_error: str | None
    last_mission: str | None
    refusals: list[str]
    pending_approval: ApprovalRequest | None
    limits: SafetyConfig
    memory: dict[str, Any] = field(default_factory=dict)  # AgentMemory.status()

    @property
    def status(self) -> MissionStatus:
        return self.progress.status

    def robot_dict(self) -> dict[str, Any]:
        """The robot's state as JSON; `connected: false` with the reason when it cannot say."""
        if self.robot is None:
            return {"connected": False, "error": self.robot_error or "no state"}
        return self.robot.to_dict()

    def to_dict(self) -> dict[str, Any]:
        return {
            **self.progress.to_dict(),
            "errors": list(self.errors),
            "estop": self.estop,
            "backend": self.backend,
            "robot": self.robot_dict(),
            "last_mission": self.last_mission,
            "refusals": list(self.refusals),
            "pending_approval": self.pending_approval.to_dict() if self.pending_approval else None,
            "limits": self.limits.model_dump(),
            "memory": dict(self.memory),
        }
