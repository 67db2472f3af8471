"""The safety governor: limits every skill call must pass before it reaches the robot.

Whoever proposed a step (a planner, the web, a test), the agent checks the whole plan here
before the first step runs, predicting the robot's path step by step. A plan with any
refused step is refused whole. `SkillContext.drive` additionally caps every velocity command.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from .config import SafetyConfig
from .robot.go2_api import TRICKS
from .skills.context import PlanEnv, PlanProblem
from .skills.registry import ValidatedCall
from .state import Pose2D


@dataclass(frozen=True)
class Refusal:
    """Why one step may not run. `step` is 1-based, as people count."""

    step: int
    skill: str
    reason: str

    def __str__(self) -> str:
        return f"step {self.step} ({self.skill}): {self.reason}"


class Governor:
    """Checks steps against `SafetyConfig`. Stateless apart from its limits."""

    def __init__(self, limits: SafetyConfig) -> None:
        self.limits = limits

    def check_plan(
        self, calls: Sequence[ValidatedCall | None], start: Pose2D, env: PlanEnv
    ) -> tuple[list[Refusal], list[Pose2D]]:
        """Check every step from `start`. Returns the refusals and the predicted path.

        None stands for a step that failed validation: it is skipped, the rest still checked.
        """
        refusals: list[Refusal] = []
        path = [start]
        pose = start
        for index, call in enumerate(calls, start=1):
            if call is None:
                continue
            try:
                reasons, poses = self._check(call, pose, env)
            except PlanProblem as exc:
                refusals.append(Refusal(index, call.name, str(exc)))
                continue
            refusals.extend(Refusal(index, call.name, r) for r in reasons)
            path.extend(poses)
            if poses:
                pose = poses[-1]
        return refusals, path

    def check_step(self, call: ValidatedCall, pose: Pose2D, env: PlanEnv) -> list[str]:
        """Re-check one step from the measured pose just before it runs."""
        try:
            return self._check(call, pose, env)[0]
        except PlanProblem as exc:
            return [str(exc)]

    def _check(
        self, call: ValidatedCall, pose: Pose2D, env: PlanEnv
    ) -> tuple[list[str], list[Pose2D]]:
        lim = self.limits
        reasons: list[str] = []
        args = call.args
        speed = getattr(args, "speed", None)
        if speed is not None:
            cap = lim.max_angular_speed if call.name == "nav.rotate" else lim.max_linear_speed
            unit = "rad/s" if call.name == "nav.rotate" else "m/s"
            setting = "max_angular_speed" if call.name == "nav.rotate" else "max_linear_speed"
            if speed > cap:
                reasons.append(f"speed {speed:g} {unit} exceeds the cap of {cap:g} {unit} "
                               f"(safety.{setting})")
        trick = getattr(args, "trick", None)
        if trick is not None and TRICKS[trick].risky and not lim.allow_risky_tricks:
            reasons.append(
                f"{trick} is a risky trick (it can hurt people or the robot) and is not "
                "approved; set safety.allow_risky_tricks: true to allow it"
            )
        seconds = getattr(args, "seconds", None)
        if seconds is not None and seconds > lim.max_wait:
            reasons.append(f"waiting {seconds:g} s exceeds safety.max_wait ({lim.max_wait:g} s)")
        poses = call.skill.predict(pose, args, env) if call.skill.predict else []
        previous = pose
        for p in poses:
            leg = math.hypot(p.x - previous.x, p.y - previous.y)
            if leg > lim.max_step_distance + 1e-9:
                reasons.append(
                    f"a straight leg of {leg:.2f} m exceeds the limit of "
                    f"{lim.max_step_distance:g} m per step (safety.max_step_distance)"
                )
                break
            previous = p
        for p in poses:
            if math.hypot(p.x, p.y) > lim.geofence_radius + 1e-9:
                reasons.append(
                    f"it would take the robot to ({p.x:.2f}, {p.y:.2f}), outside the geofence of "
                    f"{lim.geofence_radius:g} m around the origin (safety.geofence_radius)"
                )
                break
        return reasons, poses
