"""Body skills: postures and sport-mode tricks. None of them translates the robot."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Literal

from pydantic import Field, create_model

from ..robot.base import TrickInfo
from ..state import Posture
from .arguments import NoArgs, SkillArgs
from .context import SkillContext
from .registry import Skill


class SportArgs(SkillArgs):
    """`body.sport`'s arguments; `sport_skill` narrows `trick` to the robot's tricks."""

    trick: str = Field(description="a trick the robot performs")


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
    Skill(
        "body.stand",
        "Stand up.",
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
)


def sport_skill(tricks: Mapping[str, TrickInfo]) -> Skill | None:
    """`body.sport` for a robot that performs `tricks` (its `Robot.tricks`): its `trick`
    argument takes exactly their names; None for a robot without tricks (no such skill)."""
    if not tricks:
        return None
    table = dict(tricks)
    risky = ", ".join(n for n, t in table.items() if t.risky)
    args = create_model(
        "SportArgs",
        __base__=SportArgs,
        trick=(  # type: ignore[arg-type]  # a Literal built at run time
            Literal[tuple(table)],
            Field(description=f"a trick ({risky}: risky, need approval)" if risky else "a trick"),
        ),
    )

    def risk(a: SportArgs) -> str:
        if not table[a.trick].risky:
            return ""
        return f"{a.trick} is a risky trick (it can hurt people or the robot)"

    return Skill(
        "body.sport",
        "Perform a sport-mode trick in place.",
        args,
        _run_sport,
        timeout=lambda a, env: table[a.trick].duration + 15.0,
        needs_standing=True,
        risk=risk,
        seconds=lambda a: table[a.trick].duration,
        phrase=lambda a: f"do the {a.trick} trick",
    )
