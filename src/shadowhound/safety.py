"""The safety governor: limits every skill call must pass before it reaches the robot.

Whoever proposed a step (a planner, the web, a test), the agent checks the whole plan here
before the first step runs, predicting the robot's pose and posture step by step. A plan with
any refused step is refused whole; risky steps run only with approval. Limits that bind the
mission as a whole (its distance, its time, approvals) are counted against the mission's
`MissionBudget` (in `PlanEnv.budget`), so a re-plan or a react step is checked against what the
mission has already walked, spent and been granted, not from zero. `SkillContext.drive`
additionally caps every velocity and acceleration command, the agent's watchdog zeroes velocity
when the control loop stops ticking, and the agent checks each motion step's measured outcome.
"""

from __future__ import annotations

import fnmatch
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from . import geofence, units
from .budget import out_of_time
from .config import SafetyConfig
from .errors import PlanProblem
from .skills import SkillRegistry, default_registry, paths
from .skills.arguments import argument_kind
from .skills.context import PlanEnv
from .skills.registry import Skill, ValidatedCall
from .state import (
    Pose2D,
    Posture,
    RobotState,
    carried,
    normalize_angle,
    position_unknown,
)


@dataclass(frozen=True)
class Refusal:
    """Why one step may not run (or may run only with approval). `step` is 1-based."""

    step: int
    skill: str
    reason: str

    def __str__(self) -> str:
        return f"step {self.step} ({self.skill}): {self.reason}"


@dataclass
class PlanCheck:
    """The governor's verdict on a plan and the path it predicts (start pose first)."""

    refusals: list[Refusal] = field(default_factory=list)
    approvals: list[Refusal] = field(default_factory=list)
    path: list[Pose2D] = field(default_factory=list)
    distance: float = 0.0
    notes: list[str] = field(default_factory=list)  # what the check could not establish


class Governor:
    """Checks steps against `SafetyConfig`. Stateless apart from its limits.

    What it knows of a skill it reads from the skill's declarations (`Skill`: moves, runs
    standing, posture after, low battery, risk, seconds, waits), never from its name. `skills`
    (the agent's registry; default: the built-in skills) only names, in a refusal, what may
    run on a low battery.
    """

    def __init__(
        self, limits: SafetyConfig, auto_stand: bool = True, skills: SkillRegistry | None = None
    ) -> None:
        self.limits = limits
        self.auto_stand = auto_stand
        self.skills = skills if skills is not None else default_registry()

    def check_plan(
        self, calls: Sequence[ValidatedCall | None], start: RobotState, env: PlanEnv
    ) -> PlanCheck:
        """Check every step from `start`. None stands for a step that failed validation: it
        is skipped and the rest still checked."""
        check = PlanCheck(path=[start.pose])
        if start.battery is None:  # say so, rather than pass a level nobody measured
            check.notes.append(
                f"battery level unknown (the robot reports none): the battery "
                f"floor of {self.limits.battery_floor:g}% "
                "(safety.battery_floor) cannot be checked"
            )
        pose, posture = start.pose, start.posture
        budget = env.budget
        walked = budget.travelled(start) if budget else 0.0
        seconds = budget.elapsed() if budget else 0.0
        for index, call in enumerate(calls, start=1):
            if call is None:
                continue
            try:
                reasons, poses, needs_approval = self._check(call, pose, posture, start, env)
            except PlanProblem as exc:
                check.refusals.append(Refusal(index, call.name, str(exc)))
                continue
            legs = paths.legs(pose, poses)
            check.distance += sum(legs)
            reasons += self._mission_distance(walked, check.distance)
            seconds += self._least_seconds(call, sum(legs))
            reasons += self._mission_time(seconds)
            check.refusals += [Refusal(index, call.name, r) for r in reasons]
            if needs_approval:
                check.approvals.append(Refusal(index, call.name, needs_approval))
            check.path.extend(poses)
            pose = poses[-1] if poses else pose
            posture = call.skill.posture_after(posture)
        return check

    def check_outcome(
        self, call: ValidatedCall, before: RobotState, after: RobotState, env: PlanEnv
    ) -> str:
        """Compare where a motion step should have ended with where the robot measurably is.

        Returns why the outcome is off ("" when it is within tolerance): a step whose robot did
        not get there is reported failed, never as done.
        """
        if not call.skill.moves or call.skill.predict is None:
            return ""
        # Where the step began, in the frame it ended in: when SLAM relocalized the robot on
        # the way (map -> odom jumped), odometry, which no correction moves, carries it over.
        began = before.pose
        if after.relocalized != before.relocalized:
            began = carried(began, before, after)
        try:
            expected = call.skill.predict(began, call.args, env)
        except PlanProblem:  # the map changed on the way (a re-plan): the skill itself
            return ""  # measured its arrival in closed loop

        if not expected:
            return ""
        want = expected[-1]
        off = math.hypot(after.x - want.x, after.y - want.y)
        turn = abs(math.degrees(normalize_angle(after.yaw - want.yaw)))
        if after.relocalized != before.relocalized:
            # The skill planned again from the corrected pose (a goal on the map) or carried its
            # turn over the jump: the heading it ended on is its closed loop's (a goto with no
            # heading asked faces its last leg's way, not the first plan's); where is judged.
            turn = 0.0
        lim = self.limits
        if off <= lim.outcome_tolerance and turn <= lim.outcome_tolerance_deg:
            return ""
        return (
            f"outcome check failed: expected to end at ({want.x:.2f}, {want.y:.2f}, "
            f"{math.degrees(want.yaw):.0f} deg) but measured ({after.x:.2f}, {after.y:.2f}, "
            f"{math.degrees(after.yaw):.0f} deg): {off:.2f} m and {turn:.0f} degrees off "
            "(safety.outcome_tolerance, outcome_tolerance_deg)"
        )

    def check_step(self, call: ValidatedCall, state: RobotState, env: PlanEnv) -> list[str]:
        """Re-check one step from the measured state just before it runs.

        With the mission's budget in `env`, this is also the last gate for the mission's limits:
        a risky step runs only if a person approved this very call, and the distance walked so
        far plus this step's must fit (with `outcome_tolerance` of slack, since the plan it
        belongs to already passed on predictions and each step may end that far off).
        """
        try:
            reasons, poses, needs_approval = self._check(
                call, state.pose, state.posture, state, env
            )
        except PlanProblem as exc:
            return [str(exc)]
        budget = env.budget
        if budget is None:
            return reasons
        if needs_approval and not budget.granted(call):
            reasons.append(f"not approved: {needs_approval}")
        distance = sum(paths.legs(state.pose, poses))
        reasons += self._mission_distance(
            budget.travelled(state), distance, self.limits.outcome_tolerance
        )
        elapsed = budget.elapsed()
        if elapsed > self.limits.max_mission_duration + 1e-9:
            reasons.append(out_of_time(self.limits.max_mission_duration))
        else:
            reasons += self._mission_time(elapsed + self._least_seconds(call, distance))
        return reasons

    def _mission_distance(self, walked: float, planned: float, slack: float = 0.0) -> list[str]:
        """The mission's distance limit: what was walked so far plus what is planned."""
        limit = self.limits.max_mission_distance
        total = walked + planned
        if total <= limit + slack + 1e-9:
            return []
        already = f" in all ({walked:.1f} m walked already)" if walked > 0 else ""
        return [
            f"the mission would travel {total:.1f} m{already}, more than the limit of "
            f"{limit:g} m (safety.max_mission_distance)"
        ]

    def _mission_time(self, seconds: float) -> list[str]:
        """The mission's time limit, against the robot-clock time used so far plus at least
        what the steps up to here will take."""
        limit = self.limits.max_mission_duration
        if seconds <= limit + 1e-9:
            return []
        return [
            f"the mission would take at least {seconds:.1f} s on the robot's clock, more "
            f"than the limit of {limit:g} s (safety.max_mission_duration)"
        ]

    def _least_seconds(self, call: ValidatedCall, distance: float) -> float:
        """A lower bound on a step's robot time (never more than it can take): its distance at
        the speed cap, what the skill declares it surely takes (a wait, a trick). Turns and
        posture changes count as free."""
        return distance / self.limits.max_linear_speed + call.skill.least_seconds(call.args)

    def _low_battery_skills(self) -> list[str]:
        """The skills that may run below the battery floor (they walk nowhere)."""
        return [s.name for s in self.skills if s.low_battery]

    def _check(
        self,
        call: ValidatedCall,
        pose: Pose2D,
        posture: Posture,
        start: RobotState,
        env: PlanEnv,
    ) -> tuple[list[str], list[Pose2D], str]:
        lim = self.limits
        name, args = call.name, call.args
        # start.battery None: unknown, said once in check_plan's notes
        reasons = self.skill_rules(call.skill, start.battery)
        reasons += self._speed_caps(call)
        seconds = call.skill.waits(args) if call.skill.waits is not None else None
        if seconds is not None and seconds > lim.max_wait:
            reasons.append(f"waiting {seconds:g} s exceeds safety.max_wait ({lim.max_wait:g} s)")
        if call.skill.runs_standing and posture is not Posture.STANDING and not self.auto_stand:
            reasons.append(
                f"the robot will be {posture.value} here; add body.stand before it "
                "(motion.auto_stand is off)"
            )
        approval = ""
        risk = call.skill.why_risky(args)
        if risk and not lim.allow_risky_tricks:
            approval = f"{risk} and needs approval, or safety.allow_risky_tricks: true"
        if call.skill.moves and (why := position_unknown(pose)):
            raise PlanProblem(
                f"{why}: a step that moves the robot cannot be checked against the limits, "
                "the geofence and the map from there"
            )
        poses = call.skill.predict(pose, args, env) if call.skill.predict else []
        lost = next((p.unknown() for p in poses if p.unknown()), "")
        if lost:
            raise PlanProblem(f"the step's predicted path has a point that is not finite ({lost})")
        distance = getattr(args, "distance", None)
        what = name if distance is None else f"{name} {distance:g} m"
        reasons += self.path_problems(pose, poses, env, what)
        return reasons, poses, approval

    def skill_rules(self, skill: Skill, battery: float | None) -> list[str]:
        """Why `skill` may not run now, whatever its arguments and wherever the robot is: the
        allow and deny lists and the battery floor (`battery` percent; None: not known, not
        checked). Teleoperation's motion passes these too (teleop.py)."""
        lim, name = self.limits, skill.name
        reasons: list[str] = []
        if lim.allow_skills is not None and not _matches(name, lim.allow_skills):
            reasons.append(f"{name} is not in safety.allow_skills ({', '.join(lim.allow_skills)})")
        if _matches(name, lim.deny_skills):
            reasons.append(f"{name} is in safety.deny_skills")
        if battery is not None and battery < lim.battery_floor and not skill.low_battery:
            reasons.append(
                f"the battery is at {battery:.0f}%, below the floor of "
                f"{lim.battery_floor:g}% (safety.battery_floor): only "
                f"{', '.join(self._low_battery_skills())} are allowed"
            )
        return reasons

    def _speed_caps(self, call: ValidatedCall) -> list[str]:
        """Every speed argument against its cap, by the kind of quantity it is declared as."""
        lim = self.limits
        caps = {
            units.SPEED: (lim.max_linear_speed, "max_linear_speed"),
            units.ANGULAR_SPEED: (lim.max_angular_speed, "max_angular_speed"),
        }
        reasons = []
        for name, info in type(call.args).model_fields.items():
            kind = argument_kind(info)
            speed = getattr(call.args, name)
            if kind not in caps or speed is None:
                continue
            cap, setting = caps[kind]
            if speed > cap:
                reasons.append(
                    f"{name} {speed:g} {kind.unit} exceeds the cap of {cap:g} "
                    f"{kind.unit} (safety.{setting})"
                )
        return reasons

    def path_problems(
        self, pose: Pose2D, poses: list[Pose2D], env: PlanEnv, what: str
    ) -> list[str]:
        """Why the straight legs from `pose` through `poses` may not be walked (skills/paths.py:
        the step limit per leg, the geofences, and with a map anything in the way)."""
        return paths.path_problems(self.limits, pose, poses, env, what)


def inside_polygon(x: float, y: float, polygon: Sequence[tuple[float, float]]) -> bool:
    """Is (x, y) inside the polygon or on its boundary?"""
    return geofence.PolygonFence(polygon).contains((x, y))


def _matches(name: str, patterns: Sequence[str]) -> bool:
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)
