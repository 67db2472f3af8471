"""body.look_up: a skill of the tests' own, written as a new skill is: one file, no edit elsewhere.

Everything the rest of the house must know of it (it runs standing, may not run on a low
battery, a steep look needs approval, it holds the view for `hold` seconds, its output is an
answer, memory keeps it as an observation, how a call is said) is declared on its `Skill`.
It stays in the tests: the `Robot` protocol has no head pitch, so on a robot it would only
describe the camera's view, which `perception.describe` already does.
"""

from __future__ import annotations

from pydantic import Field

from shadowhound.skills import Angle, Duration, Skill, SkillArgs, SkillContext
from shadowhound.skills.sense import describe_frame

STEEP = 45.0  # degrees; beyond it the robot's weight shifts back far enough to tip it


class LookUpArgs(SkillArgs):
    degrees: Angle = Field(30.0, ge=0, le=60, description="how far to raise the head, degrees")
    hold: Duration = Field(1.0, ge=0, le=30, description="seconds to hold the view")


def _run(ctx: SkillContext, a: LookUpArgs) -> str:
    ctx.ensure_standing()
    end = ctx.robot.now() + a.hold
    while ctx.robot.now() < end - 1e-9:
        ctx.robot.sleep(min(ctx.period, end - ctx.robot.now()))
        ctx.check()
    seen = describe_frame(ctx.camera_frame(), "What is above me?", ctx.vision)
    return f"looking up {a.degrees:g} degrees: {seen}"


def _risk(a: LookUpArgs) -> str:
    if a.degrees <= STEEP:
        return ""
    return f"looking up {a.degrees:g} degrees can tip the robot over backwards"


SKILL = Skill(
    "body.look_up",
    "Raise the head by some degrees, hold the view, and say what is above.",
    LookUpArgs,
    _run,
    timeout=lambda a, env: a.hold + 15.0,
    needs_standing=True,
    risk=_risk,
    seconds=lambda a: a.hold,
    reports=True,
    remembered_as="observation",
    phrase=lambda a: f"look up {a.degrees:g} degrees",
)
