"""Body skills: postures and sport-mode tricks. None of them translates the robot."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from ..robot.go2.api import TRICKS
from ..state import Posture
from .arguments import NoArgs, SkillArgs
from .context import SkillContext
from .registry import Skill

TrickName = Literal[tuple(TRICKS)]  # type: ignore[valid-type]


class SportArgs(SkillArgs):
    trick: TrickName = Field(  # type: ignore[valid-type]
        description="a trick (flips, jumps, pounce, handstand, bound: risky, need approval)"
    )


def _posture_runner(target: Posture, done: str):  # type: ignore[no-untyped-def]
    def run(ctx: SkillContext, _a: NoArgs) -> str:
        before = ctx.robot.get_state().posture
        if before is not Posture.STANDING or target is not Posture.STANDING:
            ctx.robot.stop()
        ctx.robot.set_posture(target)
        ctx.check()
        return f"already {target.value}" if before is target else done

    return run


def _run_sport(ctx: SkillContext, a: SportArgs) -> str:
    ctx.ensure_standing()
    ctx.robot.perform(a.trick)
    ctx.check()
    return f"performed {str(a.trick).replace('_', ' ')}"


def _risk(a: SportArgs) -> str:
    if not TRICKS[a.trick].risky:
        return ""
    return f"{a.trick} is a risky trick (it can hurt people or the robot)"


SKILLS = (
    Skill(
        "body.stand",
        "Stand up (from sitting or lying).",
        NoArgs,
        _posture_runner(Posture.STANDING, "stood up"),
        timeout=10.0,
        posture=Posture.STANDING,
        phrase=lambda a: "stand up",
    ),
    Skill(
        "body.sit",
        "Sit down.",
        NoArgs,
        _posture_runner(Posture.SITTING, "sat down"),
        timeout=10.0,
        posture=Posture.SITTING,
        low_battery=True,
        phrase=lambda a: "sit down",
    ),
    Skill(
        "body.lie_down",
        "Lie down.",
        NoArgs,
        _posture_runner(Posture.LYING, "lay down"),
        timeout=10.0,
        posture=Posture.LYING,
        low_battery=True,
        phrase=lambda a: "lie down",
    ),
    Skill(
        "body.sport",
        "Perform a Unitree sport-mode trick in place.",
        SportArgs,
        _run_sport,
        timeout=lambda a, env: TRICKS[a.trick].duration + 15.0,
        needs_standing=True,
        risk=_risk,
        seconds=lambda a: TRICKS[a.trick].duration,
        phrase=lambda a: f"do the {a.trick} trick",
    ),
)
