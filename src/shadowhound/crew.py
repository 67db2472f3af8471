"""What every mission of one agent shares: the `Crew` the agent builds once and hands to each
`MissionRun`, and the `StopSignal` that cancel, the e-stop and the watchdog set."""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from . import events as ev
from .approval import ApprovalDesk
from .config import ShadowHoundConfig
from .diagnostics import MissionTracker
from .errors import MissionCancelled
from .llm.backend import LLMBackend
from .memory.service import AgentMemory
from .planning import Planner, PlanningContext
from .result import MissionResult
from .robot.base import Robot
from .safety import Governor, Watchdog
from .skills import SkillRegistry
from .speech import Voice
from .state import CameraFrame, RobotState


class StopSignal:
    """Why a mission must stop: a cancel, the latched e-stop, or the agent's own cause (the
    watchdog). `cancelled` is the event every wait in a mission watches."""

    def __init__(self) -> None:
        self.cancelled = threading.Event()
        self.estop_latched = False
        self.cause: str | None = None  # set when the agent itself stops a mission

    def reason(self) -> str:
        if self.estop_latched:
            return "e-stop pressed"
        return self.cause or "mission cancelled"


Vision = Callable[[CameraFrame, str], str]


@dataclass
class Crew:
    """What every mission of one agent shares. Built once by the agent."""

    settings: ShadowHoundConfig
    registry: SkillRegistry
    governor: Governor
    robot: Robot
    memory: AgentMemory
    events: ev.EventBus
    tracker: MissionTracker
    stop: StopSignal
    approvals: ApprovalDesk
    history: deque[MissionResult]
    planner_kind: str  # the planning configured (what MissionResult.planner records)
    camera: Callable[[], CameraFrame | None]
    vision: Vision | None
    arm_watchdog: Callable[[], Watchdog | None]
    places: Callable[[], dict[str, tuple[float, float]]]  # the profile's, then taught ones
    summaries: Callable[[], list[str]]  # recent missions, one line each, oldest first
    voice: Voice  # what the robot says passes here: cleaned, cut, rate-limited

    def planning_context(
        self, text: str, planner: Planner | None, state: RobotState
    ) -> PlanningContext | None:
        """What the planner (or a model's chat, for None) may read; None for planners that read
        nothing (the offline rules), so no history query or memory search is spent on them."""
        if planner is not None and not planner.needs_context:
            return None
        rag = self.settings.memory.enable_rag and self.settings.backend != "offline"
        belief = self.robot.belief()
        seen = {o.name: (o.x, o.y) for o in belief.objects} if belief is not None else {}
        return PlanningContext(
            registry=self.registry,
            state=state,
            places=self.places(),
            history=self.summaries(),
            cancelled=self.stop.cancelled,
            memories=self.memory.search(text) if rag and text else [],
            objects=seen,
        )

    def note_error(self, text: str) -> None:
        self.tracker.note_error(text)


def vision_for(
    backend: LLMBackend | None, settings: ShadowHoundConfig, stop: StopSignal
) -> Vision | None:
    """The model's image describer when it is configured as vision-capable; a cancel or e-stop
    abandons its request and cancels the step."""
    if not settings.llm.vision or backend is None:
        return None
    from .llm.vision import describe_image

    max_side = settings.llm.vision_max_side

    def look(frame: CameraFrame, question: str) -> str:
        answer = describe_image(backend, frame, question, max_side, stop.cancelled)
        if stop.cancelled.is_set():  # the request was abandoned: the step is cancelled
            raise MissionCancelled(stop.reason())
        return answer

    return look
