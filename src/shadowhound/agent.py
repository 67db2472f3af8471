"""RobotAgent, the facade: text in, a checked plan, skills on the robot, a MissionResult out.

Pure Python: no ROS, web or model library is imported here. Interfaces call this public API
and subscribe to its events. `execute_mission` runs in the caller's thread, one mission at a
time; `estop`, `cancel`, `get_diagnostics` and `update_camera_image` are safe from any thread.

The agent holds what missions share (robot, planner, the one model backend, governor, memory,
events) and hands each mission to a `MissionRun` (mission.py), each chat question to a chat
(conversation.py) with a `ChatContext`, and its state to `Diagnostics` (diagnostics.py).

Long because: it is the brain's whole public API in one facade (missions, approvals, control
from any thread, information); each method is a few lines handing off to the modules above.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from . import events as ev
from .approval import ApprovalDesk
from .camera import to_camera_frame
from .checking import new_mission_id
from .config import ShadowHoundConfig
from .conversation import Chat, ChatContext, ModelChat, answer_offline
from .crew import CameraFeed, Crew, StopSignal, vision_for
from .diagnostics import Diagnostics, MissionTracker
from .logbook import Logbook
from .memory.places import Places
from .memory.service import AgentMemory
from .mission import MissionRun
from .plan import Plan, SkillCall
from .planning import FixedPlanner, Planner, make_planner
from .result import MissionResult
from .robot.base import NO_TRICKS, Robot, RobotError, TrickInfo
from .safety import Governor
from .skills import SkillRegistry, default_registry
from .speech import Voice
from .state import CameraFrame, RobotState
from .watchdog import Watchdog

if TYPE_CHECKING:
    from .llm.backend import LLMBackend

log = logging.getLogger(__name__)


@dataclass
class RobotAgentConfig:
    """How to build an agent. Anything left None is made from `settings`."""

    robot: Robot | None = None
    settings: ShadowHoundConfig = field(default_factory=ShadowHoundConfig)
    planner: Planner | None = None
    registry: SkillRegistry | None = None
    backend: LLMBackend | None = None  # the language model's client (one for everything)


class RobotAgent:
    """Plans missions into validated skill calls and runs them on a robot."""

    def __init__(self, config: RobotAgentConfig | ShadowHoundConfig | None = None) -> None:
        if isinstance(config, ShadowHoundConfig):
            config = RobotAgentConfig(settings=config)
        self.config = config or RobotAgentConfig()
        self.settings = self.config.settings
        self.registry = self.config.registry or default_registry(self._tricks())
        self.governor = Governor(
            self.settings.safety, self.settings.motion.auto_stand, self.registry
        )
        self._approvals = ApprovalDesk()
        self._watchdog: Watchdog | None = None
        self._stop = StopSignal()
        # Places for this process until initialize(); the robot's own, as every memory is.
        self._memory = AgentMemory(
            self.settings, skills=self.registry, robot=self.settings.robot.identity
        )
        self._robot = self.config.robot
        self._planner = self.config.planner
        self._backend = self.config.backend
        self._events = ev.EventBus()
        self._mission_lock = threading.Lock()
        self._tracker = MissionTracker()
        self._camera = CameraFeed()
        self._logbook = Logbook(self._memory, self.settings.agent.conversation_history_size)
        self._chat: Chat = answer_offline
        self._crew: Crew | None = None

    def _tricks(self) -> Mapping[str, TrickInfo]:
        """The tricks `body.sport` offers: the given robot's (one that names none has none),
        else those of the backend the profile chooses, known before it is built."""
        if self.config.robot is not None:
            return getattr(self.config.robot, "tricks", NO_TRICKS)
        from .robot.factory import tricks_of

        return tricks_of(self.settings.robot)

    # -- life cycle ------------------------------------------------------------------------

    def initialize(self) -> bool:
        """Create the robot, the model backend and the planner if not given. Raises
        ConfigError on a bad setup (e.g. BackendUnavailable naming the URL and the model)."""
        if self._crew is not None:
            return True
        s = self.settings
        if self._robot is None:
            from .robot.factory import make_robot

            self._robot = make_robot(s)
        self._robot.watch_estop(lambda on: self.estop() if on else self.release_estop())
        self._camera.attach(self._robot)
        watchdog = self._watchdog = Watchdog(self._robot.stop, self._watchdog_tripped)
        if self._backend is None and s.backend != "offline":
            from .llm.backend import LLMBackend

            self._backend = LLMBackend(s.backend, s.llm)
        if self._planner is None:
            self._planner = make_planner(s, self._backend, tricks=self.registry.tricks())
        if self._backend is not None:
            if s.llm.check_on_start:
                self._backend.check()
            self._chat = ModelChat(self._backend, s.agent.conversation_history_size)
        if s.memory.enabled or s.memory.enable_rag:
            self._memory = AgentMemory.open(
                s, self._backend, skills=self.registry, robot=s.robot.identity
            )
            self.add_listener(self._memory.on_event)
            # Reads the history database from now on (nothing is logged before initialize).
            self._logbook = Logbook(self._memory, s.agent.conversation_history_size)
        self._crew = Crew(
            settings=s,
            registry=self.registry,
            governor=self.governor,
            robot=self._robot,
            memory=self._memory,
            events=self._events,
            tracker=self._tracker,
            stop=self._stop,
            approvals=self._approvals,
            logbook=self._logbook,
            planner_kind=self._planner.kind,
            camera=self._camera,
            vision=vision_for(self._backend, self.settings, self._stop),
            watchdog=watchdog,
            places=Places(s.places, self._memory.places),
            voice=Voice(s),
        )
        return True

    def cleanup(self) -> None:
        """Cancel any mission, stop the robot and release it."""
        self._stop.cancelled.set()
        if self._robot is not None:
            self._robot.stop()
            self._robot.close()
        if self._watchdog is not None:
            self._watchdog.close()
            self._watchdog = None
        self._memory.close()

    @property
    def robot(self) -> Robot:
        self.initialize()
        assert self._robot is not None
        return self._robot

    @property
    def planner(self) -> Planner:
        self.initialize()
        assert self._planner is not None
        return self._planner

    @property
    def backend(self) -> LLMBackend | None:
        """The language model's client (None offline): the planner, chat, vision and memory
        embeddings all use this one."""
        self.initialize()
        return self._backend

    def add_listener(self, listener: ev.Listener) -> Any:
        """Call `listener(MissionEvent)` on every event. Returns a function that unsubscribes."""
        return self._events.subscribe(listener)

    # -- missions ----------------------------------------------------------------------------

    def execute_mission(self, text: str, mission_id: str | None = None) -> MissionResult:
        """Plan `text`, check every step, run it. Never raises for bad input or robot faults.

        `mission_id` lets an interface name the mission before it starts (default: a new id).
        """
        return self._execute(text, self.planner, mission_id)

    def run_plan(
        self, calls: list[SkillCall], text: str = "", mission_id: str | None = None
    ) -> MissionResult:
        """Run explicit skill calls (from the web, a test, a script) through the same checks."""
        plan = Plan(
            list(calls), text=text or "explicit plan", planner="explicit", planned_by="explicit"
        )
        return self._execute(plan.text, FixedPlanner(plan), mission_id)

    def dry_run(self, text: str, mission_id: str | None = None) -> MissionResult:
        """Plan and check `text` without moving: the plan, the predicted path, any refusals."""
        run = self._new_run(text, self.planner, mission_id)
        if self._mission_lock.acquire(blocking=False):  # no mission runs: an earlier cancel or
            self._stop.cancelled.clear()  # e-stop must not abandon this plan (a later one does)
            self._mission_lock.release()
        return run.dry_run()

    def _execute(self, text: str, planner: Planner, mission_id: str | None) -> MissionResult:
        run = self._new_run(text, planner, mission_id)
        if not self._mission_lock.acquire(blocking=False):
            return run.refuse(
                "another mission is running; wait for it to finish or cancel it", record=False
            )
        try:
            return run.execute()
        finally:
            self._mission_lock.release()

    def _new_run(self, text: str, planner: Planner, mission_id: str | None) -> MissionRun:
        self.initialize()
        assert self._crew is not None
        return MissionRun(self._crew, planner, new_mission_id(mission_id), text)

    # -- approvals -----------------------------------------------------------------------------

    @property
    def approvals_enabled(self) -> bool:
        return self._approvals.enabled

    @approvals_enabled.setter
    def approvals_enabled(self, enabled: bool) -> None:
        self._approvals.enabled = enabled

    def enable_approvals(self, enabled: bool = True) -> None:
        """Say that an interface can ask a person to approve risky plans."""
        self._approvals.enabled = enabled

    def approve(self, request_id: str | None = None) -> bool:
        """Approve the pending plan (or the one with this request or mission id)."""
        return self._approvals.decide(True, request_id)

    def reject(self, request_id: str | None = None, reason: str = "") -> bool:
        return self._approvals.decide(False, request_id, reason)

    def pending_approval(self) -> dict[str, Any] | None:
        request = self._approvals.pending()
        return request.to_dict() if request else None

    # -- control from any thread -----------------------------------------------------------

    def cancel(self) -> None:
        """Stop the running mission within one control tick and leave the robot stopped."""
        self._stop.cancelled.set()
        if self._robot is not None:
            self._robot.stop()

    def estop(self) -> None:
        """Emergency stop: latched until `release_estop()`. Also cancels planning in flight.
        The hard stop comes before the cancel wakes the mission's thread to wind down. The
        robot's own e-stop source (`Robot.watch_estop`: a ROS topic) calls this too."""
        self._stop.estop_latched = True  # a flag: no thread wakes on it
        try:
            if self._robot is not None:
                self._robot.emergency_stop()
        finally:
            self._stop.cancelled.set()  # even when the robot's stop raised
        self._tracker.note_error("e-stop pressed")
        self._events.emit(ev.EstopChanged(self._tracker.mission_id, True))

    def release_estop(self) -> None:
        self._stop.estop_latched = False
        if self._robot is not None:
            self._robot.release_estop()
        self._events.emit(ev.EstopChanged(self._tracker.mission_id, False))

    @property
    def estop_latched(self) -> bool:
        return self._stop.estop_latched

    def _watchdog_tripped(self, message: str) -> None:
        log.error(message)
        self._tracker.note_error(message)
        self._stop.cause = message
        self._stop.cancelled.set()  # the hung skill fails as soon as it ticks again

    # -- information -------------------------------------------------------------------------

    def chat(self, text: str) -> str:
        """Answer a question about the robot and its missions. Never moves the robot."""
        if not isinstance(text, str) or not text.strip():
            return "Ask me something, for example: where are you? how is your battery?"
        answer = self._chat(text[: self.settings.agent.max_mission_chars], self._chat_context())
        if self._crew is not None:  # built by the chat's context
            self._crew.say_result(answer)
        return answer

    def _chat_context(self) -> ChatContext:
        self.initialize()
        crew = self._crew
        assert crew is not None
        return ChatContext(
            robot=crew.robot,
            camera=crew.camera,
            tracker=crew.tracker,
            estop=self.estop_latched,
            skills=crew.registry,
            missions=crew.logbook,
            memory=crew.memory,
            planner=self.planner,
            briefing=crew,
        )

    def diagnostics(self) -> Diagnostics:
        """What the agent is doing now, as one typed snapshot."""
        progress, errors = self._tracker.snapshot()
        last = self._logbook.last()
        state, problem = None, None
        try:
            state = self.robot.get_state()
        except RobotError as exc:
            problem = str(exc)
        return Diagnostics(
            progress=progress,
            errors=errors,
            estop=self.estop_latched,
            backend=self.settings.backend,
            robot=state,
            robot_error=problem,
            last_mission=last.summary() if last else None,
            refusals=list(last.refusals) if last else [],
            pending_approval=self._approvals.pending(),
            limits=self.settings.safety,
            memory=self._memory.status(),
        )

    def get_diagnostics(self) -> dict[str, Any]:
        """`diagnostics()` as JSON (the Python API's and the web API's form)."""
        return self.diagnostics().to_dict()

    def get_robot_status(self) -> dict[str, Any]:
        """The robot's state as JSON; `connected: false` with the reason when it cannot say."""
        try:
            return self.robot.get_state().to_dict()
        except RobotError as exc:
            return {"connected": False, "error": str(exc)}

    def get_robot_state(self) -> RobotState:
        return self.robot.get_state()

    def get_available_skills(self) -> list[dict[str, Any]]:
        return self.registry.describe()

    @property
    def history(self) -> list[MissionResult]:
        return self._logbook.results()

    def update_camera_image(self, frame: Any) -> None:
        """Store the latest camera frame (CameraFrame, JPEG/PNG bytes or an HxW[x3] array).

        Raises ValueError for data that is not an image.
        """
        self._camera.give(to_camera_frame(frame))

    def latest_frame(self) -> CameraFrame | None:
        """The latest camera frame: the one an interface gave, else the robot's own camera."""
        if self._camera.given is None:
            self.initialize()  # the robot's own camera: the robot is built on first use
        return self._camera.latest()

    @property
    def memory(self) -> AgentMemory:
        """History, taught places and retrieval memory (see shadowhound.memory)."""
        return self._memory

    def recent_missions(self, limit: int = 10) -> list[dict[str, Any]]:
        """This robot's missions (`robot_id`), newest first: id, mission, status, success,
        response, started_at. From the history database when memory is enabled (so it survives
        restarts), else from this process."""
        return self._logbook.recent(limit)

    def recent_summaries(self) -> list[str]:
        """Oldest first, as one line each, for prompts and chat."""
        return self._logbook.summaries()


MissionExecutor = RobotAgent
MissionExecutorConfig = RobotAgentConfig
