"""What the offline planner says when it cannot plan a request.

`NotUnderstood` carries the reason one clause could not be planned; `failure` turns the clauses
that failed, and the steps understood so far, into the `PlanningError` the user sees.
"""

from __future__ import annotations

from functools import cache

from shadowhound.errors import NotUnderstood as NotUnderstood
from shadowhound.plan import PlanningError, SkillCall
from shadowhound.skills import SkillRegistry, default_registry

CAPABILITIES = (
    "I can stand, sit, lie down, move/strafe/turn by a distance or angle, go to a position or a "
    "named place, patrol, walk a square, wait, do tricks (hello, dance, stretch, ...), describe "
    "what I see, report status, say things aloud ('say hello', 'say what you see'), and stop."
)


def describe(step: SkillCall) -> str:
    """A short description of a step, for error messages: its skill's phrase (`Skill.say`)."""
    skill = _skills().find(step.skill) if isinstance(step.skill, str) else None
    if skill is None or not isinstance(step.args, dict):
        return str(step.skill)
    # As proposed, unchecked: a step out of range (move 5000 m) is still said as asked.
    return skill.say(skill.args_model.model_construct(**step.args))


@cache
def _skills() -> SkillRegistry:
    """The skills this planner plans: the built-in ones (its sentences name no others)."""
    return default_registry()


def failure(steps: list[SkillCall], failed: list[tuple[str, str]]) -> PlanningError:
    understood = [describe(s) for s in steps]
    shown = "; ".join(understood[:12]) + ("; ..." if len(understood) > 12 else "")
    quoted = ", ".join(
        f'"{label}"' + (f" ({reason})" if reason else "") for label, reason in failed
    )
    message = (f"I understood: {shown}. " if understood else "") + f"I did not understand {quoted}."
    return PlanningError(
        f"{message} {CAPABILITIES}",
        understood=understood,
        not_understood=[label for label, _ in failed],
    )
