"""Checking a plan before anything moves: every step validated, then the governor's verdict.

Pure: it reads the registry, the governor and the settings, and touches no robot. Every batch
of steps of a mission passes here (the first plan, a re-plan, each react step, a dry run) with
the mission's `PlanEnv`, whose budget makes the governor count what the mission already used.
"""

from __future__ import annotations

import dataclasses
import math
import uuid
from dataclasses import dataclass
from typing import Any

from .config import ShadowHoundConfig
from .errors import PlanProblem
from .plan import Plan, Watch, branch_problems, oversize
from .result import StepResult, StepStatus
from .robot.base import Robot
from .safety import Governor
from .skills import PlanEnv, SkillRegistry, SkillValidationError, ValidatedCall
from .skills.watches import GUARD_WHEN, check_watches
from .state import Pose2D, RobotState, position_unknown
from .world import check_leg

REACH_MARGIN = 0.05  # metres kept short of where the body would touch what is in the way


@dataclass
class CheckedPlan:
    """A plan after validation and the governor: what runs, what is wrong, what needs a yes."""

    steps: list[StepResult]  # one record per proposed step, numbered from `first`
    calls: list[ValidatedCall]  # the valid calls (all of them when `problems` is empty)
    problems: list[str]  # validation errors and refusals: any one refuses the plan
    approvals: list[str]  # why a person must approve before it runs
    path: list[Pose2D]  # predicted poses, the start first
    invalid: list[list[str]]  # per proposed step, why it is not a valid call (empty: valid)
    forecasts: list[str]  # what the check could not predict, per step ("step 1 (...): ...")


def check_plan(
    plan: Plan,
    registry: SkillRegistry,
    governor: Governor,
    settings: ShadowHoundConfig,
    env: PlanEnv,
    start: RobotState,
    first: int = 1,
    robot: Robot | None = None,
) -> CheckedPlan:
    """Validate every step and run the governor over the whole plan from `start` (as if no
    watch ever fired: a watch only shortens a step). Each step's watches must be observable on
    `robot`, or the plan is refused naming them. A plan larger than the `agent` limits is
    refused whole before any step is validated (`plan.oversize`)."""
    too_big = oversize(plan.steps, settings.agent)
    if too_big:
        return _too_big(plan, too_big, start, first, settings.agent.max_steps)
    calls, problems, invalid = _validate(plan, registry)
    for i, c in enumerate(calls, first):
        if c is None or not (c.watches or c.guard):
            continue
        if robot is None:
            problems.append(f"step {i}: its conditions can only be checked against the robot")
            continue
        problems += [f"step {i}: {p}" for p in check_watches(c.watches, robot, env.vocabulary)]
        if c.guard is not None:
            found = check_watches([c.guard], robot, env.vocabulary, GUARD_WHEN)
            problems += [f"step {i}: {p}" for p in found]
    if all(c is not None for c in calls):  # each branch is decided once: say it can be
        problems += branch_problems([c.guard for c in calls if c is not None], first)
    steps = [
        StepResult(i, c.skill, plain_args(c.args), c.label, watches=_watch_records(c))
        for i, c in enumerate(plan.steps, first)
    ]
    calls = _within_reach(calls, start, env, first, plan.notes)
    verdict = governor.check_plan(calls, start, env)
    forecasts = [
        f"step {i} ({c.name}): {text}"
        for i, c in enumerate(calls, first)
        if c is not None
        and c.skill.forecast is not None
        and (text := c.skill.forecast(c.args, env))
    ]
    plan.notes.extend(n for n in verdict.notes if n not in plan.notes)

    def renumber(r: Any) -> str:
        return str(r).replace(f"step {r.step} ", f"step {r.step + first - 1} ", 1)

    problems += [renumber(r) for r in verdict.refusals]
    approvals = [renumber(r) for r in verdict.approvals]
    if settings.safety.require_approval:
        approvals.append("every plan needs approval (safety.require_approval)")
    valid = [c for c in calls if c is not None]
    if problems:
        for s in steps:
            s.status = StepStatus.SKIPPED
    else:
        for s, c in zip(steps, valid, strict=True):
            s.args = c.args_dict()
    return CheckedPlan(
        steps=steps,
        calls=valid,
        problems=problems,
        approvals=approvals,
        path=verdict.path,
        invalid=invalid,
        forecasts=forecasts,
    )


def _too_big(
    plan: Plan, problems: list[str], start: RobotState, first: int, most: int
) -> CheckedPlan:
    """A plan refused for its size: records for at most `most` of its steps, none validated."""
    steps = [
        StepResult(i, str(c.skill)[:100], plain_args(c.args), str(c.label)[:200])
        for i, c in enumerate(plan.steps[:most], first)
    ]
    for s in steps:
        s.status = StepStatus.SKIPPED
    return CheckedPlan(
        steps=steps,
        calls=[],
        problems=list(problems),
        approvals=[],
        path=[start.pose],
        invalid=[list(problems) for _ in steps],
        forecasts=[],
    )


def _within_reach(
    calls: list[ValidatedCall | None],
    start: RobotState,
    env: PlanEnv,
    first: int,
    notes: list[str],
) -> list[ValidatedCall | None]:
    """A straight walk that goes until something happens ("walk forward until you see the
    box"), or unless something is in the way, goes at most as far as the map says is clear:
    its distance is cut to short of what is in the way, said in a note. A watch may only
    shorten a step, so this is the walk the governor then checks in full (as if the watch
    never fired); every other step is as given."""
    if env.belief is None:
        return calls
    pose, fitted = start.pose, []
    for i, call in enumerate(calls, first):
        poses: list[Pose2D] = []
        predict = call.skill.predict if call is not None else None
        if position_unknown(pose):
            predict = None  # nothing is known from here: the governor refuses, saying why
        if call is not None and predict is not None:
            try:
                poses = predict(pose, call.args, env)
            except PlanProblem:
                poses = []  # the governor says why
            distance = getattr(call.args, "distance", None)
            cut_by = [w for w in call.watches if w.when == "until" or w.kind == "in_the_way"]
            if cut_by and len(poses) == 1 and isinstance(distance, float) and distance:
                leg = check_leg(env.belief, (pose.x, pose.y), (poses[0].x, poses[0].y))
                reach = math.floor(max(0.0, leg.distance - REACH_MARGIN) * 100) / 100
                if not leg.clear and leg.obstacle != "unmapped space" and reach > 0:
                    args = call.args.model_copy(update={"distance": math.copysign(reach, distance)})
                    call = dataclasses.replace(call, args=args)
                    poses = predict(pose, call.args, env)
                    notes.append(
                        f"step {i} ({call.name}) goes at most {reach:g} m, short of "
                        f"{leg.obstacle} in the way ({cut_by[0].describe()})"
                    )
        fitted.append(call)
        pose = poses[-1] if poses else pose
    return fitted


def _validate(
    plan: Plan, registry: SkillRegistry
) -> tuple[list[ValidatedCall | None], list[str], list[list[str]]]:
    """Validate every step; invalid ones become None so the rest can still be checked."""
    problems: list[str] = []
    calls: list[ValidatedCall | None] = []
    invalid: list[list[str]] = []
    if not plan.steps:
        problems.append("the plan has no steps")
    for index, call in enumerate(plan.steps, start=1):
        try:
            calls.append(registry.validate(call))
            invalid.append([])
        except SkillValidationError as exc:
            calls.append(None)
            invalid.append(list(exc.problems))
            problems.extend(f"step {index}: {p}" for p in exc.problems)
    return calls, problems, invalid


def _watch_records(call: Any) -> list[dict[str, Any]]:
    """A proposed step's guard and watches for the record (whatever a planner sent)."""
    watches = getattr(call, "watches", ())
    guard = getattr(call, "guard", None)
    records = [guard.to_dict()] if isinstance(guard, Watch) else []
    return records + ([w.to_dict() for w in watches if isinstance(w, Watch)] if watches else [])


def plain_args(args: Any) -> dict[str, Any]:
    """Proposed arguments as given, for the record (a model may send anything)."""
    return dict(args) if isinstance(args, dict) else {"_invalid": repr(args)}


def new_mission_id(given: str | None = None) -> str:
    """`given` if it is a valid id (1-64 of [A-Za-z0-9_-]), else a fresh one when None."""
    if given is None:
        return uuid.uuid4().hex[:12]
    if (
        not isinstance(given, str)
        or not (0 < len(given) <= 64)
        or not all(c.isascii() and (c.isalnum() or c in "-_") for c in given)
    ):
        raise ValueError(f"a mission id must be 1 to 64 letters, digits, '-' or '_', got {given!r}")
    return given
