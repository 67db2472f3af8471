"""What every mission of one agent shares: the `Crew` the agent builds once and hands to each
`MissionRun`, the `StopSignal` that cancel, the e-stop and the watchdog set, and the
`CameraFeed` skills and chat look through.

The crew holds services, not the agent's methods: the places (`memory.places.Places`), the
missions run (`logbook.Logbook`), the memory, the camera feed, the model's vision, the
watchdog, the voice.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass

from . import events as ev
from .approval import ApprovalDesk
from .config import ShadowHoundConfig
from .diagnostics import MissionTracker
from .errors import MissionCancelled, RobotError
from .llm.backend import LLMBackend
from .logbook import Logbook
from .memory.places import Places
from .memory.service import AgentMemory
from .planning import Planner, PlanningContext
from .robot.base import Robot
from .safety import Governor
from .skills import SkillRegistry
from .speech import Voice
from .state import CameraFrame, RobotState
from .watchdog import Watchdog

log = logging.getLogger(__name__)


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


class CameraFeed:
    """The latest camera frame: the one an interface gave last, else the robot's own camera
    (once `attach`ed). Safe from any thread: a frame is replaced whole."""

    def __init__(self) -> None:
        self._given: CameraFrame | None = None
        self._robot: Robot | None = None

    def give(self, frame: CameraFrame) -> None:
        self._given = frame

    @property
    def given(self) -> CameraFrame | None:
        """The frame an interface gave, None before one."""
        return self._given

    def attach(self, robot: Robot) -> None:
        """Look through `robot`'s camera when no interface gave a frame."""
        self._robot = robot

    def latest(self) -> CameraFrame | None:
        if self._given is not None:
            return self._given
        return self._robot.get_camera_frame() if self._robot is not None else None


class ModelVision:
    """The model's image describer; a cancel or e-stop abandons its request and cancels the
    step."""

    def __init__(self, backend: LLMBackend, max_side: int, stop: StopSignal) -> None:
        self.backend = backend
        self.max_side = max_side
        self.stop = stop

    def describe(self, frame: CameraFrame, question: str) -> str:
        from .llm.vision import describe_image

        stop = self.stop
        answer = describe_image(self.backend, frame, question, self.max_side, stop.cancelled)
        if stop.cancelled.is_set():  # the request was abandoned: the step is cancelled
            raise MissionCancelled(stop.reason())
        return answer


@dataclass(kw_only=True)
class Crew:
    """What every mission of one agent shares. Built once by the agent, with keywords."""

    settings: ShadowHoundConfig
    registry: SkillRegistry
    governor: Governor
    robot: Robot
    memory: AgentMemory  # taught places and sightings, recall
    events: ev.EventBus
    tracker: MissionTracker
    stop: StopSignal
    approvals: ApprovalDesk
    logbook: Logbook  # every result is added; recent missions for prompts
    planner_kind: str  # the planning configured (what MissionResult.planner records)
    camera: CameraFeed
    vision: ModelVision | None  # None: no vision-capable model is configured
    watchdog: Watchdog  # armed per step on a robot whose clock runs in real time
    places: Places  # the profile's, then taught ones
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
            places=self.places.positions(),
            history=self.logbook.summaries(finished_only=planner is not None),
            cancelled=self.stop.cancelled,
            memories=self.memory.search(text) if rag and text else [],
            objects=seen,
        )

    def note_error(self, text: str) -> None:
        self.tracker.note_error(text)

    def say_result(self, text: str) -> None:
        """With `speech.speak_results`, an outcome or an answer said on the robot's speaker
        through the voice (cleaned, cut, rate-limited); why it was not is logged, never raised."""
        if not self.settings.speech.speak_results or not text.strip():
            return
        try:
            saying = self.voice.speak(self.robot, text)
        except (ValueError, RobotError) as exc:
            log.warning("not said aloud: %s", exc)
            return
        if saying.why_silent:
            log.info("not said aloud: %s", saying.why_silent)

    def arm_watchdog(self) -> Watchdog | None:
        """Arm the watchdog for a step on a robot whose clock runs in real time (a simulator
        at time scale 0 only moves when the loop ticks, so there is nothing to guard)."""
        robot = self.robot
        if not robot.realtime:
            return None
        period = 1.0 / self.settings.motion.control_rate_hz
        self.watchdog.arm(
            max(self.settings.safety.watchdog_timeout, 3 * period * robot.time_scale),
            self.settings.safety.watchdog_grace,
        )
        return self.watchdog


def vision_for(
    backend: LLMBackend | None, settings: ShadowHoundConfig, stop: StopSignal
) -> ModelVision | None:
    """The model's image describer when it is configured as vision-capable, else None."""
    if not settings.llm.vision or backend is None:
        return None
    return ModelVision(backend, settings.llm.vision_max_side, stop)
