"""RobotAgent: the brain. Text in, a checked plan, skills on the robot, a MissionResult out.

Pure Python: no ROS, web or model library is imported here. Interfaces call this public API
and subscribe to its events. `execute_mission` runs in the caller's thread, one mission at a
time; `estop`, `cancel`, `get_diagnostics` and `update_camera_image` are safe from any thread.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from . import events as ev
from .admission import ESTOP_LATCHED, mission_text_problem
from .approval import ApprovalDesk, ApprovalRequest
from .budget import MissionBudget
from .camera import to_camera_frame
from .checking import CheckedPlan, check_plan, new_mission_id, plain_args
from .config import ConfigError, ShadowHoundConfig
from .conversation import answer_offline
from .memory.places import known_places
from .memory.service import AgentMemory
from .plan import Plan, PlanningError, SkillCall, Usage
from .planning import FixedPlanner, Planner, PlanningContext, make_planner
from .result import (
    MissionResult,
    MissionStatus,
    StepResult,
    StepStatus,
    Timing,
    compose_response,
)
from .robot.base import Robot, RobotError
from .safety import Governor, Watchdog
from .skills import (
    MissionCancelled,
    PlanEnv,
    SkillContext,
    SkillError,
    SkillRegistry,
    SkillValidationError,
    ValidatedCall,
    default_registry,
)
from .skills.context import robot_belief
from .skills.objects import see_at_start
from .state import CameraFrame, RobotState

log = logging.getLogger(__name__)



@dataclass
class RobotAgentConfig:
    """How to build an agent. Anything left None is made from `settings`."""

    robot: Robot | None = None
    settings: ShadowHoundConfig = field(default_factory=ShadowHoundConfig)
    planner: Planner | None = None
    registry: SkillRegistry | None = None


class RobotAgent:
    """Plans missions into validated skill calls and runs them on a robot."""

    def __init__(self, config: RobotAgentConfig | ShadowHoundConfig | None = None) -> None:
        if isinstance(config, ShadowHoundConfig):
            config = RobotAgentConfig(settings=config)
        self.config = config or RobotAgentConfig()
        self.settings = self.config.settings
        self.registry = self.config.registry or default_registry()
        self.governor = Governor(self.settings.safety, self.settings.motion.auto_stand,
                                 self.registry)
        self._approvals = ApprovalDesk()
        self.approvals_enabled = False
        self._watchdog: Watchdog | None = None
        self._stop_cause: str | None = None  # set when the agent itself stops a mission
        # Places for this process until initialize().
        self._memory = AgentMemory(self.settings, skills=self.registry)
        self._robot = self.config.robot
        self._planner = self.config.planner
        self._events = ev.EventBus()
        self._mission_lock = threading.Lock()
        self._state_lock = threading.Lock()
        self._cancel = threading.Event()
        self._estop_latched = False
        self._camera_frame: CameraFrame | None = None
        self._status = MissionStatus.IDLE
        self._current: dict[str, Any] = {"mission_id": None, "mission": None, "skill": None,
                                         "step": 0, "steps": 0, "progress": 0.0}
        self._errors: deque[str] = deque(maxlen=20)
        self._history: deque[MissionResult] = deque(
            maxlen=max(1, self.settings.agent.conversation_history_size)
        )
        self._chat_history: deque[dict[str, str]] = deque(
            maxlen=2 * self.settings.agent.conversation_history_size
        )
        self._initialized = False

    # -- life cycle ------------------------------------------------------------------------

    def initialize(self) -> bool:
        """Create the robot and planner if not given. Raises ConfigError on a bad setup."""
        if self._initialized:
            return True
        if self._robot is None:
            if self.settings.robot != "sim":
                raise ConfigError(
                    f"robot {self.settings.robot!r} needs a robot object (e.g. Go2RosRobot); "
                    "only the simulated robot ('sim') is built automatically"
                )
            from .robot.sim import SimRobot

            self._robot = SimRobot(self.settings.sim)
        if self._planner is None:
            self._planner = make_planner(self.settings)
        check = getattr(self._planner, "check", None)
        if check is not None and self.settings.llm.check_on_start:
            check()  # raises BackendUnavailable (a ConfigError) naming the URL and the model
        memory = self.settings.memory
        if memory.enabled or memory.enable_rag:
            self._memory = AgentMemory.open(self.settings, getattr(self._planner, "backend", None),
                                            skills=self.registry)
            self.add_listener(self._memory.on_event)
        self._initialized = True
        return True

    def cleanup(self) -> None:
        """Cancel any mission, stop the robot and release it."""
        self._cancel.set()
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

    def add_listener(self, listener: ev.Listener) -> Any:
        """Call `listener(MissionEvent)` on every event. Returns a function that unsubscribes."""
        return self._events.subscribe(listener)

    # -- missions ----------------------------------------------------------------------------

    def execute_mission(self, text: str, mission_id: str | None = None) -> MissionResult:
        """Plan `text`, check every step, run it. Never raises for bad input or robot faults.

        `mission_id` lets an interface name the mission before it starts (default: a new id).
        """
        return self._execute(text, self.planner, mission_id)

    def run_plan(self, calls: list[SkillCall], text: str = "",
                 mission_id: str | None = None) -> MissionResult:
        """Run explicit skill calls (from the web, a test, a script) through the same checks."""
        plan = Plan(list(calls), text=text or "explicit plan", planner="explicit",
                    planned_by="explicit")
        return self._execute(plan.text, FixedPlanner(plan), mission_id)

    def dry_run(self, text: str, mission_id: str | None = None) -> MissionResult:
        """Plan and check `text` without moving: the plan, the predicted path, any refusals."""
        self.initialize()
        mission_id = new_mission_id(mission_id)
        started = time.perf_counter()
        if problem := mission_text_problem(text, self.settings.agent.max_mission_chars):
            return self._refuse(mission_id, str(text)[:200], started, problem, False)
        if self._mission_lock.acquire(blocking=False):  # no mission runs: an earlier cancel or
            self._cancel.clear()  # e-stop must not abandon this plan (a later one still does)
            self._mission_lock.release()
        timing = Timing()
        env = self._plan_env()
        try:
            plan = self.planner.plan(text[: self.settings.agent.max_mission_chars],
                                     self._planning_context(text, self.planner))
        except PlanningError as exc:
            return self._refuse(mission_id, text, started, exc.message, False)
        timing.agent_duration = timing.total_duration = time.perf_counter() - started
        checked = self._prepare(plan, env, self.robot.get_state(), first=1)
        end, problems = checked.path[-1], checked.problems
        if problems:
            response = "Dry run: the plan would be refused: " + "; ".join(problems)
        else:
            response = (f"Dry run: {len(checked.steps)} step(s) would run and end near "
                        f"x={end.x:.2f} m, y={end.y:.2f} m; nothing moved.")
            if checked.approvals:
                response += " It needs approval: " + "; ".join(checked.approvals) + "."
        return MissionResult(mission_id, text, not problems, response, MissionStatus.IDLE,
                             checked.steps, self.robot.get_state(), timing, plan.usage, plan,
                             problems, None if not problems else response, True, checked.path)

    def _execute(self, text: str, planner: Planner, mission_id: str | None) -> MissionResult:
        self.initialize()
        mission_id = new_mission_id(mission_id)
        started = time.perf_counter()
        if not isinstance(text, str):
            return self._refuse(mission_id, repr(text)[:200], started,
                                f"a mission must be text, got {type(text).__name__}")
        if not self._mission_lock.acquire(blocking=False):
            return self._refuse(mission_id, text, started, "another mission is running; wait for "
                                "it to finish or cancel it", record=False)
        try:
            return self._run_mission(mission_id, text, started, planner)
        finally:
            self._mission_lock.release()

    def _run_mission(self, mission_id: str, text: str, started: float,
                     planner: Planner) -> MissionResult:
        if self._estop_latched:
            return self._refuse(mission_id, text, started, ESTOP_LATCHED)
        limit = self.settings.agent.max_mission_chars
        if problem := mission_text_problem(text, limit):
            shown = text if len(text) <= limit else text[:200] + "..."
            return self._refuse(mission_id, shown, started, problem)
        try:
            start_state = self.robot.get_state()
        except RobotError as exc:  # e.g. no odometry from a real robot: do not plan blind
            return self._refuse(mission_id, text, started,
                                f"the robot cannot report its state: {exc}")
        self._cancel.clear()
        self._stop_cause = None
        self._set_current(mission_id=mission_id, mission=text, skill=None, step=0, steps=0,
                          progress=0.0)
        self._set_status(MissionStatus.PLANNING)
        self._emit(ev.MISSION_STARTED, mission_id, mission=text)
        timing = Timing()
        env = self._plan_env()

        if getattr(planner, "mode", "plan") == "react" and hasattr(planner, "react"):
            return self._run_react(mission_id, text, started, planner, env)

        # 1. Plan. The planner never touches the robot.
        t = time.perf_counter()
        try:
            plan = planner.plan(text, self._planning_context(text, planner))
        except PlanningError as exc:
            timing.agent_duration = time.perf_counter() - t
            if self._cancel.is_set():  # the wait on the model was abandoned: stopped, not failed
                return self._finish(mission_id, text, started, timing, [], None,
                                    MissionStatus.STOPPED, self._stop_reason(), usage=exc.usage)
            return self._finish(mission_id, text, started, timing, [], None,
                                MissionStatus.FAILED, exc.message, usage=exc.usage)
        timing.agent_duration = time.perf_counter() - t
        if self._cancel.is_set():
            return self._finish(mission_id, text, started, timing, [], plan,
                                MissionStatus.STOPPED, self._stop_reason())

        # 2. Validate every step and check the whole predicted path before anything moves;
        #    risky plans wait for a person's approval.
        checked = self._prepare(plan, env, start_state, first=1)
        steps, valid, problems = checked.steps, checked.calls, checked.problems
        if not problems and checked.approvals:
            refused = self._await_approval(mission_id, text, steps, checked.approvals, env,
                                           valid)
            problems = [refused] if refused else []
        elif problems:
            problems += checked.approvals  # say everything that stands in the way at once
        if problems:
            for s in steps:
                s.status = StepStatus.SKIPPED
            stopped = self._cancel.is_set()
            return self._finish(mission_id, text, started, timing, steps, plan,
                                MissionStatus.STOPPED if stopped else MissionStatus.FAILED,
                                self._stop_reason() if stopped else
                                "Refused before moving: " + "; ".join(problems),
                                refusals=problems)
        self._emit(ev.PLAN_READY, mission_id, plan=plan.to_dict(),  # path: maps, RViz
                   path=[{"x": round(p.x, 4), "y": round(p.y, 4)} for p in checked.path])

        # 3. Run the steps in order; the first failure stops the mission and the robot.
        status, error = self._run_steps(mission_id, steps, valid, env, timing)

        # 4. A failed step may be re-planned once, from where the robot is now.
        replan = getattr(planner, "replan", None)
        if status is MissionStatus.FAILED and replan and self.settings.agent.replan_on_failure:
            done = [s.output for s in steps if s.status is StepStatus.SUCCEEDED]
            t = time.perf_counter()
            try:
                again = replan(text, self._planning_context(), done, error or "")
                plan.usage.add(again.usage)
            except PlanningError as exc:
                plan.usage.add(exc.usage)
                again = None
                error = f"{error}; re-planning failed: {exc.message}"
            timing.agent_duration += time.perf_counter() - t
            now = self._state_or_none()
            if again is not None and now is not None and not self._cancel.is_set():
                more_checked = self._prepare(again, env, now, first=len(steps) + 1)
                more, more_valid = more_checked.steps, more_checked.calls
                problems = more_checked.problems + [f"needs approval: {a}"
                                                    for a in more_checked.approvals]
                if problems:
                    error = f"{error}; the new plan was refused: {'; '.join(problems)}"
                else:
                    plan.notes.append(f"re-planned after: {error}")
                    plan.steps += again.steps
                    steps += more
                    self._set_current(steps=len(steps))
                    status, error = self._run_steps(mission_id, more, more_valid, env, timing)
            if status is MissionStatus.FAILED and self._cancel.is_set():  # while re-planning
                status, error = MissionStatus.STOPPED, self._stop_reason()
        response = compose_response(status, steps, plan, error, self.registry)
        return self._finish(mission_id, text, started, timing, steps, plan, status, response,
                            error=error)

    def _prepare(self, plan: Plan, env: PlanEnv, start: RobotState, first: int) -> CheckedPlan:
        return check_plan(plan, self.registry, self.governor, self.settings, env, start, first)

    def _await_approval(self, mission_id: str, text: str, steps: list[StepResult],
                        reasons: list[str], env: PlanEnv,
                        calls: list[ValidatedCall]) -> str | None:
        """None when a person approved (the mission's budget then holds `calls` as approved);
        otherwise the refusal."""
        if not self.approvals_enabled:
            return ("needs approval, and no interface that can ask a person is attached: "
                    + "; ".join(reasons))
        request = ApprovalRequest(mission_id, text, [s.to_dict() for s in steps], reasons,
                                  self.settings.safety.approval_timeout)
        self._approvals.open(request)  # before the event, so an instant answer finds it
        self._emit(ev.APPROVAL_REQUIRED, mission_id, request=request.to_dict())
        refused = self._approvals.wait(request, self._cancel)
        self._emit(ev.APPROVAL_DECIDED, mission_id, approved=refused is None, reason=refused)
        if refused is None and env.budget is not None:
            env.budget.grant(calls)
        return None if refused is None else f"not approved ({refused}): " + "; ".join(reasons)

    def enable_approvals(self, enabled: bool = True) -> None:
        """Say that an interface can ask a person to approve risky plans."""
        self.approvals_enabled = enabled

    def approve(self, request_id: str | None = None) -> bool:
        """Approve the pending plan (or the one with this request or mission id)."""
        return self._approvals.decide(True, request_id)

    def reject(self, request_id: str | None = None, reason: str = "") -> bool:
        return self._approvals.decide(False, request_id, reason)

    def pending_approval(self) -> dict[str, Any] | None:
        request = self._approvals.pending()
        return request.to_dict() if request else None

    def _run_steps(self, mission_id: str, steps: list[StepResult], calls: list[ValidatedCall],
                   env: PlanEnv, timing: Timing) -> tuple[MissionStatus, str | None]:
        self._set_status(MissionStatus.EXECUTING)
        self._set_current(steps=max(self._current["steps"], steps[-1].index if steps else 0))
        for position, (step, call) in enumerate(zip(steps, calls, strict=True)):
            outcome = self._run_step(mission_id, step, call, env)
            timing.execution_duration += step.duration
            timing.robot_duration += step.robot_duration
            if outcome is not MissionStatus.SUCCEEDED:
                self.robot.stop()
                for later in steps[position + 1:]:
                    later.status = StepStatus.SKIPPED
                return outcome, step.error
        return MissionStatus.SUCCEEDED, None

    def _run_react(self, mission_id: str, text: str, started: float, planner: Any,
                   env: PlanEnv) -> MissionResult:
        """The model calls one skill at a time; each passes validation and safety first."""
        timing = Timing()
        steps: list[StepResult] = []
        refusals: list[str] = []
        self._set_status(MissionStatus.EXECUTING)

        def run_step(call: SkillCall) -> str:
            step = StepResult(len(steps) + 1, str(call.skill), plain_args(call.args), call.label)
            steps.append(step)
            self._set_current(steps=len(steps))
            try:
                named = self.registry.validate(call)
            except SkillValidationError as exc:
                step.status, step.error = StepStatus.SKIPPED, "; ".join(exc.problems)
                return f"invalid call, not run: {step.error}"
            step.skill, step.args = named.name, named.args_dict()  # as a person is asked
            # Each step is a batch of one, checked against what the mission has already used.
            checked = self._prepare(Plan([call], text=text), env, self.robot.get_state(),
                                    first=step.index)
            found, valid = checked.problems, checked.calls[0]
            if not found and checked.approvals:
                refused = self._await_approval(mission_id, text, [step], checked.approvals,
                                               env, checked.calls)
                found = [refused] if refused else []
            if found:
                step.status, step.error = StepStatus.SKIPPED, "; ".join(found)
                refusals.extend(found)
                return f"refused by the safety limits, not run: {step.error}"
            outcome = self._run_step(mission_id, step, valid, env)
            timing.execution_duration += step.duration
            timing.robot_duration += step.robot_duration
            if outcome is MissionStatus.STOPPED:
                raise MissionCancelled(step.error or "mission cancelled")
            return step.output if outcome is MissionStatus.SUCCEEDED else f"failed: {step.error}"

        t = time.perf_counter()
        usage = Usage()
        status = MissionStatus.SUCCEEDED
        try:
            answer, usage, finished = planner.react(text, self._planning_context(text), run_step)
        except PlanningError as exc:
            answer, usage, finished = exc.message, exc.usage, False
            if self._cancel.is_set():  # the wait on the model was abandoned: stopped, not failed
                answer, status = self._stop_reason(), MissionStatus.STOPPED
        except MissionCancelled:
            answer, finished, status = self._stop_reason(), False, MissionStatus.STOPPED
        except RobotError as exc:
            answer, finished = f"the robot cannot report its state: {exc}", False
        timing.agent_duration = max(0.0, time.perf_counter() - t - timing.execution_duration)
        failed = [s for s in steps if s.status in (StepStatus.FAILED, StepStatus.CANCELLED)]
        if status is not MissionStatus.STOPPED and (not finished or failed or refusals):
            status = MissionStatus.FAILED
        if status is MissionStatus.SUCCEEDED and self._cancel.is_set():
            status, answer = MissionStatus.STOPPED, self._stop_reason()
        if refusals and status is MissionStatus.FAILED:
            answer = f"{answer} Refused: {'; '.join(refusals)}."
        plan = Plan([SkillCall(s.skill, s.args, s.label) for s in steps], text=text,
                    usage=usage, planner=getattr(planner, "name", "react"), planned_by="llm")
        return self._finish(mission_id, text, started, timing, steps, plan, status, answer,
                            error=None if status is MissionStatus.SUCCEEDED else answer,
                            refusals=refusals)

    def _run_step(self, mission_id: str, step: StepResult, call: ValidatedCall,
                  env: PlanEnv) -> MissionStatus:
        robot = self.robot
        step.status = StepStatus.RUNNING
        step.started_at = time.time()
        self._set_current(skill=call.name, step=step.index)
        self._emit(ev.STEP_STARTED, mission_id, step=step.to_dict())
        wall, robot_t0 = time.perf_counter(), robot.now()
        status = MissionStatus.SUCCEEDED
        watchdog = self._arm_watchdog()
        ctx = SkillContext(robot, env, self._cancel, camera=self.latest_frame,
                           vision=self._vision(), memory=self._memory,
                           on_progress=lambda f: self._step_progress(step.index, f),
                           heartbeat=watchdog.beat if watchdog else lambda _moving: None)
        try:
            before = robot.get_state()
            refused = self.governor.check_step(call, before, env)
            if refused:
                raise SkillError("refused by the safety governor: " + "; ".join(refused))
            ctx.start_clock(call.skill.timeout_for(call.args, env))
            ctx.check()
            output = call.skill.run(ctx, call.args)
            off_target = self.governor.check_outcome(call, before, robot.get_state(), env)
            if off_target:
                raise SkillError(off_target)
            step.output = "; ".join([*ctx.notes, output])
            step.status = StepStatus.SUCCEEDED
        except MissionCancelled:
            robot.stop()
            step.status, step.error = StepStatus.CANCELLED, self._stop_reason()
            status = MissionStatus.STOPPED
        except (SkillError, RobotError) as exc:
            robot.stop()
            step.status, step.error = StepStatus.FAILED, str(exc)
            status = MissionStatus.FAILED
        except Exception as exc:  # a bug in a skill must still leave the robot stopped
            log.exception("skill %s crashed", call.name)
            robot.stop()
            step.status, step.error = StepStatus.FAILED, f"internal error: {exc!r}"
            status = MissionStatus.FAILED
        if watchdog:
            watchdog.disarm()
        step.duration = time.perf_counter() - wall
        step.robot_duration = robot.now() - robot_t0
        if step.status is StepStatus.SUCCEEDED:  # a stopped step keeps the progress it made
            self._step_progress(step.index, 1.0)
        self._emit(ev.STEP_FINISHED, mission_id, step=step.to_dict())
        return status

    def _arm_watchdog(self) -> Watchdog | None:
        """Watch robots whose clock runs in real time (a simulator at time scale 0 only moves
        when the loop ticks, so there is nothing to guard)."""
        scale = float(getattr(self.robot, "time_scale", 1.0))
        if scale <= 0:
            return None
        if self._watchdog is None:
            self._watchdog = Watchdog(self.robot.stop, self._watchdog_tripped)
        period = 1.0 / self.settings.motion.control_rate_hz
        self._watchdog.arm(max(self.settings.safety.watchdog_timeout, 3 * period * scale))
        return self._watchdog

    def _watchdog_tripped(self, message: str) -> None:
        log.error(message)
        self._note_error(message)
        self._stop_cause = message
        self._cancel.set()  # the hung skill fails as soon as it ticks again

    # -- control from any thread -----------------------------------------------------------

    def cancel(self) -> None:
        """Stop the running mission within one control tick and leave the robot stopped."""
        self._cancel.set()
        if self._robot is not None:
            self._robot.stop()

    def estop(self) -> None:
        """Emergency stop: latched until `release_estop()`. Also cancels planning in flight."""
        self._estop_latched = True
        self._cancel.set()
        robot = self._robot
        if robot is not None:
            hard_stop = getattr(robot, "emergency_stop", None)
            (hard_stop or robot.stop)()
        self._note_error("e-stop pressed")
        self._emit(ev.ESTOP, self._current.get("mission_id") or "", latched=True)

    def release_estop(self) -> None:
        self._estop_latched = False
        release = getattr(self._robot, "release_estop", None)
        if release is not None:
            release()
        self._emit(ev.ESTOP, self._current.get("mission_id") or "", latched=False)

    @property
    def estop_latched(self) -> bool:
        return self._estop_latched

    def _stop_reason(self) -> str:
        if self._estop_latched:
            return "e-stop pressed"
        return self._stop_cause or "mission cancelled"

    # -- information -------------------------------------------------------------------------

    def chat(self, text: str) -> str:
        """Answer a question about the robot and its missions. Never moves the robot."""
        if not isinstance(text, str) or not text.strip():
            return "Ask me something, for example: where are you? how is your battery?"
        text = text[: self.settings.agent.max_mission_chars]
        llm_chat = getattr(self.planner, "chat", None)
        if llm_chat is None:
            return answer_offline(text, self)
        with self._state_lock:
            history = list(self._chat_history)
        answer = str(llm_chat(text, self._planning_context(text), history))
        with self._state_lock:
            self._chat_history.extend([{"role": "user", "content": text},
                                       {"role": "assistant", "content": answer}])
        return answer

    def get_diagnostics(self) -> dict[str, Any]:
        with self._state_lock:
            current = dict(self._current)
            status = self._status
            errors = list(self._errors)
        last = self._history[-1] if self._history else None
        return {
            "status": status.value,
            "mission_id": current["mission_id"],
            "mission": current["mission"],
            "current_skill": current["skill"],
            "step": current["step"],
            "steps": current["steps"],
            "progress": round(current["progress"], 3),
            "errors": errors,
            "estop": self._estop_latched,
            "backend": self.settings.backend,
            "robot": self.get_robot_status(),
            "last_mission": last.summary() if last else None,
            "refusals": list(last.refusals) if last else [],
            "pending_approval": self.pending_approval(),
            "limits": self.settings.safety.model_dump(),
            "memory": self._memory.status(),
        }

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
        return list(self._history)

    def update_camera_image(self, frame: Any) -> None:
        """Store the latest camera frame (CameraFrame, JPEG/PNG bytes or an HxW[x3] array).

        Raises ValueError for data that is not an image.
        """
        self._camera_frame = to_camera_frame(frame)

    def _vision(self) -> Any:
        """The planner's image describer when the model is configured as vision-capable."""
        if not self.settings.llm.vision:
            return None
        describe = getattr(self._planner, "describe_image", None)
        if describe is None:
            return None

        def look(frame: CameraFrame, question: str) -> str:
            answer = str(describe(frame, question, self._cancel))
            if self._cancel.is_set():  # the request was abandoned: the step is cancelled
                raise MissionCancelled(self._stop_reason())
            return answer

        return look

    def latest_frame(self) -> CameraFrame | None:
        """The latest camera frame: the one an interface gave, else the robot's own camera."""
        return self._camera_frame or self.robot.get_camera_frame()


    def _known_places(self) -> dict[str, tuple[float, float]]:
        """The profile's places, then taught ones (which win)."""
        known = known_places(self.settings.places, self._memory.places)
        return {name: place.position for name, place in known.items()}

    def _plan_env(self) -> PlanEnv:
        """The mission's environment, with a fresh budget: made once per mission."""
        state = self.robot.get_state()
        belief = robot_belief(self.robot)
        see_at_start(self.robot, belief, self._memory)  # objects in view count as known
        return PlanEnv(self.settings, state.pose, self._known_places(),
                       MissionBudget.start(state, self.robot.now), belief)

    def _planning_context(self, text: str = "", planner: Any = None) -> PlanningContext | None:
        """What the planner may read; None for planners that read nothing (the offline rules),
        so no history query or memory search is spent on them."""
        if planner is not None and not getattr(planner, "needs_context", True):
            return None
        rag = self.settings.memory.enable_rag and self.settings.backend != "offline"
        belief = robot_belief(self.robot)
        seen = {o.name: (o.x, o.y) for o in belief.objects} if belief is not None else {}
        return PlanningContext(self.registry, self.robot.get_state(), self._known_places(),
                               self.recent_summaries(), self._cancel,
                               self._memory.search(text) if rag and text else [], seen)

    @property
    def memory(self) -> AgentMemory:
        """History, taught places and retrieval memory (see shadowhound.memory)."""
        return self._memory

    def recent_missions(self, limit: int = 10) -> list[dict[str, Any]]:
        """Newest first: id, mission, status, success, response, started_at. From the history
        database when memory is enabled (so it survives restarts), else from this process."""
        rows = self._memory.recent_missions(limit)
        if rows or self._memory.history is not None:
            return rows
        return [{"id": r.mission_id, "mission": r.mission, "status": r.status.value,
                 "success": r.success, "response": r.response, "started_at": None,
                 "finished_at": None} for r in reversed(self._history)][:limit]

    def recent_summaries(self) -> list[str]:
        """Oldest first, as one line each, for prompts and chat."""
        rows = self.recent_missions(self.settings.agent.conversation_history_size)
        return [f"{r['status']}: {r['mission']!r} -> {r['response']}" for r in reversed(rows)]

    # -- bookkeeping ---------------------------------------------------------------------------

    def _state_or_none(self) -> RobotState | None:
        """The robot's state for a record; None when the robot cannot say (never raises)."""
        try:
            return self.robot.get_state()
        except RobotError as exc:
            log.warning("robot state unavailable: %s", exc)
            return None

    def _note_error(self, text: str) -> None:
        """Remember an error for diagnostics (the same one twice in a row is kept once)."""
        with self._state_lock:
            if not self._errors or self._errors[-1] != text:
                self._errors.append(text)

    def _set_status(self, status: MissionStatus) -> None:
        with self._state_lock:
            self._status = status

    def _set_current(self, **values: Any) -> None:
        with self._state_lock:
            self._current.update(values)

    def _step_progress(self, index: int, fraction: float) -> None:
        with self._state_lock:
            total = self._current["steps"] or 1
            self._current["progress"] = min(1.0, ((index - 1) + fraction) / total)

    def _emit(self, kind: str, mission_id: str, **data: Any) -> None:
        self._events.emit(ev.MissionEvent(kind, mission_id, data))

    def _refuse(self, mission_id: str, text: str, started: float, reason: str,
                record: bool = True) -> MissionResult:
        result = MissionResult(mission_id, text, False, f"Refused: {reason.rstrip('.')}.",
                               MissionStatus.FAILED, robot=self._state_or_none(), error=reason,
                               refusals=[reason])
        result.timing.total_duration = time.perf_counter() - started
        if record:
            self._note_error(reason)
            self._history.append(result)
            self._set_status(MissionStatus.FAILED)
        return result

    def _finish(self, mission_id: str, text: str, started: float, timing: Timing,
                steps: list[StepResult], plan: Plan | None, status: MissionStatus,
                response: str, *, error: str | None = None, usage: Usage | None = None,
                refusals: list[str] | None = None) -> MissionResult:
        if status is not MissionStatus.SUCCEEDED:
            self.robot.stop()
            error = error or response
            self._note_error(error)
        timing.total_duration = time.perf_counter() - started
        result = MissionResult(
            mission_id, text, status is MissionStatus.SUCCEEDED, response, status, steps,
            self._state_or_none(), timing, usage or (plan.usage if plan else Usage()), plan,
            refusals or [], error, planner=getattr(self._planner, "kind", ""),
        )
        self._history.append(result)
        self._set_status(status)
        if result.success:
            self._set_current(skill=None, progress=1.0)
        else:
            self._set_current(skill=None)
        self._emit(ev.MISSION_FINISHED, mission_id, result=result.to_dict())
        return result


MissionExecutor = RobotAgent
MissionExecutorConfig = RobotAgentConfig
