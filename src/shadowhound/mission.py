"""One mission, from text to `MissionResult`: read, plan, check, approve, execute, report.

`MissionRun` is made by the agent for each mission (and each dry run) and reads top to bottom:
`execute` (plan mode), `react` (the model proposes one call at a time) and `dry_run` all read
the mission once (its text and the robot's state), and every batch of steps they would run
passes the one `check` (checking.check_plan: validation, then the governor over the whole
predicted path) before anything moves. The run touches the robot only through the Robot
protocol and the governor's step checks.

What runs share across missions (the robot, the governor, the event bus, the progress tracker,
the e-stop and cancel signal) is the agent's `Crew` (crew.py).

Long because: the six stages of one mission (and react mode's step loop) read best together,
in order; each stage is a short method.
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any

from . import events as ev
from .admission import ESTOP_LATCHED, mission_text_problem
from .approval import ApprovalRequest
from .budget import MissionBudget
from .checking import CheckedPlan, check_plan
from .crew import Crew
from .errors import WatchFired
from .plan import Plan, PlanningError, SkillCall, Usage, Watch, branch_ways
from .planning import Planner, PlanningContext, ReplanningPlanner, StepwisePlanner
from .result import MissionResult, MissionStatus, StepResult, StepStatus, Timing, compose_response
from .robot.base import RobotError
from .skills import (
    MissionCancelled,
    PlanEnv,
    SkillContext,
    SkillError,
    ValidatedCall,
)
from .skills.motion import settle
from .skills.objects import see_at_start
from .skills.watches import Branches, fired_text
from .speech import Saying
from .state import RobotState, normalize_angle

log = logging.getLogger(__name__)


class MissionRun:
    """One mission. Make one per mission; call `execute` (or `dry_run`) once."""

    def __init__(self, crew: Crew, planner: Planner, mission_id: str, text: Any) -> None:
        self.crew = crew
        self.robot = crew.robot
        self.planner = planner
        self.id = mission_id
        self.text = text
        self.started = time.perf_counter()
        self.timing = Timing()
        self.steps: list[StepResult] = []
        self.spoke = False  # a step said something (`say`): the result is not said over it
        self.start: RobotState | None = None
        self.env: PlanEnv | None = None

    # -- the mission, stage by stage --------------------------------------------------------

    def execute(self) -> MissionResult:
        """Run the mission (the caller holds the agent's one-mission lock)."""
        refusal = self.read(moving=True)
        if refusal is not None:
            return self.refuse(refusal)
        self.begin()
        try:
            return self._from_plan_to_report()
        except Exception as exc:  # a bug anywhere after the start still ends the record
            log.exception("mission %s crashed", self.id)
            return self.report(MissionStatus.FAILED, crashed("the mission", exc), None)

    def _from_plan_to_report(self) -> MissionResult:
        if isinstance(self.planner, StepwisePlanner):
            return self.react(self.planner)
        plan = self.plan()
        if isinstance(plan, MissionResult):
            return plan
        checked = self.check(plan, self._start(), first=1)
        problems = (
            checked.problems + checked.approvals
            if checked.problems
            else self.approve(checked.steps, checked)
        )
        if problems:
            return self.refused_before_moving(plan, checked.steps, problems)
        self.emit(ev.PlanReady.of(self.id, plan, ((p.x, p.y) for p in checked.path)))
        self.steps = checked.steps
        status, error = self.run_steps(checked.steps, checked.calls)
        if status is MissionStatus.FAILED and isinstance(self.planner, ReplanningPlanner):
            status, error = self.replan(self.planner, plan, error)
        return self.report(
            status,
            compose_response(status, self.steps, plan, error, self.crew.registry),
            plan,
            error=error,
        )

    def dry_run(self) -> MissionResult:
        """Plan and check without moving: the plan, the predicted path, any refusals."""
        refusal = self.read(moving=False)
        if refusal is not None:
            return self.refuse(refusal, record=False)
        start = self._start()
        try:
            plan = self.planner.plan(self.text, self._context())
        except PlanningError as exc:
            return self.refuse(exc.message, record=False)
        except Exception as exc:  # whatever a model sent: refused, said why
            log.exception("planning %r crashed", self.text[:80])
            return self.refuse(crashed("planning", exc), record=False)
        self.timing.agent_duration = self.timing.total_duration = self._elapsed()
        checked = self.check(plan, start, first=1)
        end, problems = checked.path[-1], checked.problems
        ways = branch_ways([c.guard for c in checked.calls])
        if problems:
            response = "Dry run: the plan would be refused: " + "; ".join(problems)
        elif ways:  # which steps run is decided on the way; each way was checked
            response = (
                f"Dry run: {len(checked.steps)} step(s) planned; "
                + "; ".join(ways)
                + "; every way was checked; nothing moved."
            )
            if checked.approvals:
                response += " It needs approval: " + "; ".join(checked.approvals) + "."
        elif checked.forecasts:  # where it ends is not known before it runs
            response = (
                f"Dry run: {len(checked.steps)} step(s) would run; "
                + "; ".join(checked.forecasts)
                + "; nothing moved."
            )
        else:
            response = (
                f"Dry run: {len(checked.steps)} step(s) would run and end near "
                f"x={end.x:.2f} m, y={end.y:.2f} m; nothing moved."
            )
            if checked.approvals:
                response += " It needs approval: " + "; ".join(checked.approvals) + "."
        return MissionResult(
            mission_id=self.id,
            mission=self.text,
            success=not problems,
            response=response,
            status=MissionStatus.IDLE,
            steps=checked.steps,
            robot=self.robot.get_state(),
            timing=self.timing,
            usage=plan.usage,
            plan=plan,
            refusals=problems,
            error=None if not problems else response,
            dry_run=True,
            predicted_path=checked.path,
        )

    # 1. Read: the text, the e-stop, and the robot's state, once, before planning.

    def read(self, moving: bool) -> str | None:
        """Why the mission cannot start, or None (then `start` and `env` are set)."""
        text, limit = self.text, self.crew.settings.agent.max_mission_chars
        if not isinstance(text, str):
            self.text = repr(text)[:200]
        elif len(text) > limit:
            self.text = text[:200] + "..."
        if moving and self.crew.stop.estop_latched and isinstance(text, str):
            return ESTOP_LATCHED
        if problem := mission_text_problem(text, limit):
            return problem
        try:
            self.start = self.robot.get_state()
        except RobotError as exc:  # e.g. no odometry from a real robot: do not plan blind
            return f"the robot cannot report its state: {exc}"
        belief = self.robot.belief()
        see_at_start(self.robot, belief, self.crew.memory)  # objects in view count as known
        self.env = PlanEnv(
            self.crew.settings,
            mission_start=self.start.pose,
            places=self.crew.places.positions(),
            budget=MissionBudget.start(self.start, self.robot.now),
            belief=belief,
            vocabulary=self.robot.vocabulary(),
            secondhand=self.crew.memory.secondhand(),
        )
        return None

    def begin(self) -> None:
        self.crew.stop.cancelled.clear()
        self.crew.stop.cause = None
        self.crew.tracker.start(self.id, self.text)
        self.emit(ev.MissionStarted(self.id, self.text))

    # 2. Plan. The planner never touches the robot.

    def plan(self) -> Plan | MissionResult:
        t = time.perf_counter()
        try:
            plan = self.planner.plan(self.text, self._context())
        except PlanningError as exc:
            self.timing.agent_duration = time.perf_counter() - t
            if self.crew.stop.cancelled.is_set():  # the wait on the model was abandoned
                return self.report(
                    MissionStatus.STOPPED, self.crew.stop.reason(), None, usage=exc.usage
                )
            return self.report(MissionStatus.FAILED, exc.message, None, usage=exc.usage)
        except Exception as exc:  # a planner's bug (or a reply it cannot hold) ends it failed
            log.exception("planning %r crashed", self.text[:80])
            self.timing.agent_duration = time.perf_counter() - t
            return self.report(MissionStatus.FAILED, crashed("planning", exc), None)
        self.timing.agent_duration = time.perf_counter() - t
        if self.crew.stop.cancelled.is_set():
            return self.report(MissionStatus.STOPPED, self.crew.stop.reason(), plan)
        return plan

    # 3. Check: every batch of steps (plan, re-plan, react step, dry run) passes here.

    def check(self, plan: Plan, start: RobotState, first: int) -> CheckedPlan:
        c = self.crew
        return check_plan(
            plan, c.registry, c.governor, c.settings, self._env(), start, first, self.robot
        )

    # 4. Approve: risky plans wait for a person.

    def approve(self, steps: list[StepResult], checked: CheckedPlan) -> list[str]:
        """[] when nothing needs approval or a person approved (the mission's budget then
        holds the calls as approved); otherwise the refusal."""
        if not checked.approvals:
            return []
        reasons = checked.approvals
        c = self.crew
        if not c.approvals.enabled:
            return [
                "needs approval, and no interface that can ask a person is attached: "
                + "; ".join(reasons)
            ]
        request = ApprovalRequest(
            mission_id=self.id,
            mission=self.text,
            steps=[s.to_dict() for s in steps],
            reasons=reasons,
            timeout=c.settings.safety.approval_timeout,
        )
        c.approvals.open(request)  # before the event, so an instant answer finds it
        self.emit(ev.ApprovalRequired(self.id, request))
        refused = c.approvals.wait(request, c.stop.cancelled)
        self.emit(ev.ApprovalDecided(self.id, refused is None, refused))
        budget = self._env().budget
        if refused is None and budget is not None:
            budget.grant(checked.calls)
        if refused is None:
            return []
        return [f"not approved ({refused}): " + "; ".join(reasons)]

    def refused_before_moving(
        self, plan: Plan, steps: list[StepResult], problems: list[str]
    ) -> MissionResult:
        for s in steps:
            s.status = StepStatus.SKIPPED
        self.steps = steps
        if self.crew.stop.cancelled.is_set():
            return self.report(
                MissionStatus.STOPPED, self.crew.stop.reason(), plan, refusals=problems
            )
        return self.report(
            MissionStatus.FAILED,
            "Refused before moving: " + "; ".join(problems),
            plan,
            refusals=problems,
        )

    # 5. Execute: the steps in order; the first failure stops the mission and the robot.

    def run_steps(
        self, steps: list[StepResult], calls: list[ValidatedCall]
    ) -> tuple[MissionStatus, str | None]:
        self.crew.tracker.set_status(MissionStatus.EXECUTING)
        self.crew.tracker.at_least_steps(steps[-1].index if steps else 0)
        ways = Branches([c.guard for c in calls], self.robot, self.crew.settings.sim.body_radius)
        for position, (step, call) in enumerate(zip(steps, calls, strict=True)):
            taken = ""
            if call.guard is not None:
                runs, taken = self.guarded(step, call.guard, ways, position)
                if not runs:
                    continue  # a branch not taken: skipped, saying why
            outcome = self.run_step(step, call, taken)
            if outcome is MissionStatus.SUCCEEDED and self.crew.stop.cancelled.is_set():
                if position + 1 == len(steps):
                    break  # "until I say stop" was the last step: done as asked
                outcome = MissionStatus.STOPPED  # after a person's stop nothing more moves
                step.error = "a person said stop: the steps after it were not run"
            if outcome is not MissionStatus.SUCCEEDED:
                self.robot.stop()
                for later in steps[position + 1 :]:
                    later.status = StepStatus.SKIPPED
                return outcome, step.error
        return MissionStatus.SUCCEEDED, None

    def replan(
        self, planner: ReplanningPlanner, plan: Plan, error: str | None
    ) -> tuple[MissionStatus, str | None]:
        """A failed step may be re-planned once, from where the robot is now."""
        status: MissionStatus = MissionStatus.FAILED
        if not self.crew.settings.agent.replan_on_failure:
            return status, error
        done = [s.output for s in self.steps if s.status is StepStatus.SUCCEEDED]
        t = time.perf_counter()
        now = self._state_or_none()
        again: Plan | None = None
        try:
            again = planner.replan(self.text, self._context(now, ""), done, error or "")
            plan.usage.add(again.usage)
        except PlanningError as exc:
            plan.usage.add(exc.usage)
            error = f"{error}; re-planning failed: {exc.message}"
        except Exception as exc:
            log.exception("re-planning %r crashed", self.text[:80])
            error = f"{error}; {crashed('re-planning', exc)}"
        self.timing.agent_duration += time.perf_counter() - t
        now = self._state_or_none()
        if again is not None and now is not None and not self.crew.stop.cancelled.is_set():
            more = self.check(again, now, first=len(self.steps) + 1)
            problems = more.problems + [f"needs approval: {a}" for a in more.approvals]
            if problems:
                error = f"{error}; the new plan was refused: {'; '.join(problems)}"
            else:
                plan.notes.append(f"re-planned after: {error}")
                plan.steps += again.steps
                self.steps += more.steps
                self.crew.tracker.set_steps(len(self.steps))
                status, error = self.run_steps(more.steps, more.calls)
        if status is MissionStatus.FAILED and self.crew.stop.cancelled.is_set():
            status, error = MissionStatus.STOPPED, self.crew.stop.reason()
        return status, error

    def react(self, planner: StepwisePlanner) -> MissionResult:
        """The model calls one skill at a time; each passes the same check first."""
        refusals: list[str] = []
        stop = self.crew.stop
        self.crew.tracker.set_status(MissionStatus.EXECUTING)

        def run_step(call: SkillCall) -> str:
            # Each step is a batch of one, checked against what the mission already used.
            checked = self.check(
                Plan([call], text=self.text), self.robot.get_state(), first=len(self.steps) + 1
            )
            step = checked.steps[0]
            step.skill = str(call.skill)
            self.steps.append(step)
            self.crew.tracker.set_steps(len(self.steps))
            if checked.invalid[0]:
                step.status, step.error = StepStatus.SKIPPED, "; ".join(checked.invalid[0])
                return f"invalid call, not run: {step.error}"
            valid = checked.calls[0]
            step.skill, step.args = valid.name, valid.args_dict()  # as a person is asked
            found = checked.problems or self.approve([step], checked)
            if found:
                step.status, step.error = StepStatus.SKIPPED, "; ".join(found)
                refusals.extend(found)
                return f"refused by the safety limits, not run: {step.error}"
            outcome = self.run_step(step, valid)
            if outcome is MissionStatus.STOPPED:
                raise MissionCancelled(step.error or "mission cancelled")
            return step.output if outcome is MissionStatus.SUCCEEDED else f"failed: {step.error}"

        t = time.perf_counter()
        usage = Usage()
        status = MissionStatus.SUCCEEDED
        try:
            answer, usage, finished = planner.react(self.text, self._context(), run_step)
        except PlanningError as exc:
            answer, usage, finished = exc.message, exc.usage, False
            if stop.cancelled.is_set():  # the wait on the model was abandoned: stopped
                answer, status = stop.reason(), MissionStatus.STOPPED
        except MissionCancelled:
            answer, finished, status = stop.reason(), False, MissionStatus.STOPPED
        except RobotError as exc:
            answer, finished = f"the robot cannot report its state: {exc}", False
        except Exception as exc:  # the robot is stopped by the report
            log.exception("planning %r crashed", self.text[:80])
            answer, finished = crashed("planning", exc), False
        self.timing.agent_duration = max(
            0.0, time.perf_counter() - t - self.timing.execution_duration
        )
        failed = [s for s in self.steps if s.status in (StepStatus.FAILED, StepStatus.CANCELLED)]
        if status is not MissionStatus.STOPPED and (not finished or failed or refusals):
            status = MissionStatus.FAILED
        if status is MissionStatus.SUCCEEDED and stop.cancelled.is_set():
            status, answer = MissionStatus.STOPPED, stop.reason()
        if refusals and status is MissionStatus.FAILED:
            answer = f"{answer} Refused: {'; '.join(refusals)}."
        plan = Plan(
            [SkillCall(s.skill, s.args, s.label) for s in self.steps],
            text=self.text,
            usage=usage,
            planner=planner.name,
            planned_by="llm",
        )
        return self.report(
            status,
            answer,
            plan,
            refusals=refusals,
            error=None if status is MissionStatus.SUCCEEDED else answer,
        )

    def guarded(
        self, step: StepResult, guard: Watch, ways: Branches, position: int
    ) -> tuple[bool, str]:
        """Whether a guarded step runs (a way of "if ... otherwise ...", decided once per
        branch: `Branches`), and why; a step not run is skipped, saying why."""
        runs, said = ways.runs(position, guard)
        if not runs:
            step.status = StepStatus.SKIPPED
            step.output = f"skipped: {said}"
            self.emit(ev.StepFinished.of(self.id, step))
        return runs, said

    def run_step(self, step: StepResult, call: ValidatedCall, taken: str = "") -> MissionStatus:
        """One checked step on the robot: the governor's step check, the skill, its outcome."""
        robot, c = self.robot, self.crew
        env = self._env()
        step.status = StepStatus.RUNNING
        step.started_at = time.time()
        c.tracker.step_started(call.name, step.index)
        self.emit(ev.StepStarted.of(self.id, step))
        wall, robot_t0 = time.perf_counter(), robot.now()
        status = MissionStatus.SUCCEEDED
        watchdog = c.arm_watchdog()
        ctx = SkillContext(
            robot,
            env,
            c.stop.cancelled,
            camera=c.camera.latest,
            vision=c.vision.describe if c.vision is not None else None,
            memory=c.memory,
            on_progress=lambda f: c.tracker.step_progress(step.index, f),
            heartbeat=watchdog.beat if watchdog else lambda _moving: None,
            say=lambda text: self.say(step, text),
            answer=self.answer,
        )
        if taken:  # why a guarded step runs: its branch was taken
            ctx.notes.append(taken)
        try:
            before = robot.get_state()
            refused = c.governor.check_step(call, before, env)
            if refused:
                raise SkillError("refused by the safety governor: " + "; ".join(refused))
            ctx.start_clock(call.skill.timeout_for(call.args, env))
            ctx.watch(call.watches)
            ctx.check()
            output = call.skill.run(ctx, call.args)
            if call.skill.moves or ctx.ledger is not None:
                # A step that moved the robot ends at rest, whatever the skill did last: the
                # next step then starts from rest, and the outcome is judged there.
                settle(ctx)
            off_target = c.governor.check_outcome(call, before, robot.get_state(), env)
            if off_target:
                raise SkillError(off_target)
            step.output = "; ".join([*ctx.notes, output])
            step.status = StepStatus.SUCCEEDED
        except WatchFired as fired:  # the robot is stopped; what it did counts, as far as it got
            robot.stop()
            said = f"{_so_far(before, robot)}, {fired_text(fired.watch, fired.observed)}"  # type: ignore[arg-type]
            step.output = "; ".join([*ctx.notes, said])
            self.emit(ev.WatchFiredEvent(self.id, step.index, said))
            if getattr(fired.watch, "when", "") == "until":
                step.status = StepStatus.SUCCEEDED  # done: what it waited for came
            else:
                step.status, step.error = StepStatus.CANCELLED, said
                status = MissionStatus.STOPPED
        except MissionCancelled:
            robot.stop()
            asked = _until_stopped(call, c.stop)
            if asked is not None:  # "until I say stop", and a person said it: done as asked
                said = f"{_so_far(before, robot)}, stopped: you said stop ({asked})"
                step.output = "; ".join([*ctx.notes, said])
                step.status = StepStatus.SUCCEEDED
                self.emit(ev.WatchFiredEvent(self.id, step.index, said))
            else:
                step.status, step.error = StepStatus.CANCELLED, c.stop.reason()
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
        self.timing.execution_duration += step.duration
        self.timing.robot_duration += step.robot_duration
        if step.status is StepStatus.SUCCEEDED:  # a stopped step keeps the progress it made
            c.tracker.step_progress(step.index, 1.0)
        self.emit(ev.StepFinished.of(self.id, step))
        return status

    def say(self, step: StepResult, text: str) -> Saying:
        """A step's words through the agent's voice; every interface sees them (`Spoken`)."""
        try:
            saying = self.crew.voice.speak(self.robot, text)
        except ValueError as exc:
            raise SkillError(str(exc)) from exc
        self.spoke = True
        self.emit(ev.Spoken(self.id, saying.text, step.index, saying.why_silent))
        return saying

    def answer(self) -> str | None:
        """The output of this mission's latest successful step that answers the user."""
        for done in reversed(self.steps):
            skill = self.crew.registry.find(done.skill)
            if done.status is StepStatus.SUCCEEDED and skill is not None and skill.reports:
                return done.output
        return None

    # 6. Report: one record for the history, the diagnostics and the listeners.

    def report(
        self,
        status: MissionStatus,
        response: str,
        plan: Plan | None,
        *,
        error: str | None = None,
        usage: Usage | None = None,
        refusals: list[str] | None = None,
    ) -> MissionResult:
        c = self.crew
        if status is not MissionStatus.SUCCEEDED:
            self.robot.stop()
            error = error or response
            c.note_error(error)
        self.timing.total_duration = self._elapsed()
        result = MissionResult(
            mission_id=self.id,
            mission=self.text,
            success=status is MissionStatus.SUCCEEDED,
            response=response,
            status=status,
            steps=self.steps,
            robot=self._state_or_none(),
            timing=self.timing,
            usage=usage or (plan.usage if plan else Usage()),
            plan=plan,
            refusals=refusals or [],
            error=error,
            planner=c.planner_kind,
        )
        c.logbook.add(result)
        c.tracker.finished(status)
        self._say_result(response)
        self.emit(ev.MissionFinished(self.id, result))
        return result

    def _say_result(self, response: str) -> None:
        """The outcome on the robot's speaker (`Crew.say_result`), unless a step spoke."""
        if not self.spoke:
            self.crew.say_result(response)

    def refuse(self, reason: str, record: bool = True) -> MissionResult:
        """Refused before anything started (no mission events)."""
        result = MissionResult(
            mission_id=self.id,
            mission=str(self.text),
            success=False,
            response=f"Refused: {reason.rstrip('.')}.",
            status=MissionStatus.FAILED,
            robot=self._state_or_none(),
            error=reason,
            refusals=[reason],
        )
        result.timing.total_duration = self._elapsed()
        if record:
            self.crew.note_error(reason)
            self._say_result(result.response)
            self.crew.logbook.add(result)
            self.crew.tracker.set_status(MissionStatus.FAILED)
        return result

    # -- helpers ----------------------------------------------------------------------------

    def emit(self, event: ev.MissionEvent) -> None:
        self.crew.events.emit(event)

    def _start(self) -> RobotState:
        assert self.start is not None, "read() first"
        return self.start

    def _env(self) -> PlanEnv:
        assert self.env is not None, "read() first"
        return self.env

    def _context(
        self, state: RobotState | None = None, text: str | None = None
    ) -> PlanningContext | None:
        return self.crew.planning_context(
            self.text if text is None else text, self.planner, state or self._start()
        )

    def _elapsed(self) -> float:
        return time.perf_counter() - self.started

    def _state_or_none(self) -> RobotState | None:
        """The robot's state for a record; None when the robot cannot say (never raises)."""
        try:
            return self.robot.get_state()
        except RobotError as exc:
            log.warning("robot state unavailable: %s", exc)
            return None


def crashed(what: str, exc: BaseException) -> str:
    """Why a stage ended on an unexpected exception, for people: "planning failed: internal
    error (RecursionError: maximum recursion depth exceeded ...); nothing more was run"."""
    said = " ".join(str(exc).split())
    said = said[:197] + "..." if len(said) > 200 else said
    return (
        f"{what} failed: internal error ({type(exc).__name__}{': ' + said if said else ''}); "
        "nothing more was run"
    )


def _so_far(before: RobotState, robot: Any) -> str:
    """What a step stopped by a watch did: "moved 1.84 m, turned 12 degrees" ("did not move")."""
    now = robot.last_state()
    moved = math.hypot(now.x - before.x, now.y - before.y)
    turned = abs(math.degrees(normalize_angle(now.yaw - before.yaw)))
    parts = [f"moved {moved:.2f} m"] if moved >= 0.01 else []
    parts += [f"turned {turned:.0f} degrees"] if turned >= 1 else []
    return ", ".join(parts) or "did not move"


def _until_stopped(call: ValidatedCall, stop: Any) -> str | None:
    """The words of `call`'s "until I say stop", when a person's plain stop (not the e-stop,
    not the watchdog) ended it; else None."""
    if stop.estop_latched or stop.cause:
        return None
    for w in call.watches:
        if w.kind == "operator_stop" and w.when == "until":
            return w.words or w.describe()
    return None
