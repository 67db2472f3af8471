"""Body skills: postures and sport-mode tricks. None of them translates the robot."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from ..robot.go2_api import TRICKS
from ..state import Posture
from .arguments import NoArgs, SkillArgs
from .context import SkillContext
from .registry import Skill

TrickName = Literal[tuple(TRICKS)]  # type: ignore[valid-type]


class SportArgs(SkillArgs):
    trick: TrickName = Field(  # type: ignore[valid-type]
        description="trick name; risky: " + ", ".join(t.name for t in TRICKS.values() if t.risky)
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


SKILLS = (
    Skill("body.stand", "Stand up (from sitting or lying).", NoArgs,
          _posture_runner(Posture.STANDING, "stood up"), timeout=10.0),
    Skill("body.sit", "Sit down.", NoArgs, _posture_runner(Posture.SITTING, "sat down"),
          timeout=10.0),
    Skill("body.lie_down", "Lie down.", NoArgs,
          _posture_runner(Posture.LYING, "lay down"), timeout=10.0),
    Skill(
        "body.sport",
        "Perform a Unitree sport-mode trick in place. Risky tricks need "
        "safety.allow_risky_tricks.",
        SportArgs,
        _run_sport,
        timeout=lambda a, env: TRICKS[a.trick].duration + 15.0,
    ),
)
