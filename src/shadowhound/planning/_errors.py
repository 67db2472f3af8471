"""What the offline planner says when it cannot plan a request.

`NotUnderstood` carries the reason one clause could not be planned; `failure` turns the clauses
that failed, and the steps understood so far, into the `PlanningError` the user sees.
"""

from __future__ import annotations

from typing import Any

from shadowhound.errors import NotUnderstood as NotUnderstood
from shadowhound.plan import PlanningError, SkillCall
from shadowhound.planning._numbers import format_number as _fmt

CAPABILITIES = (
    "I can stand, sit, lie down, move/strafe/turn by a distance or angle, go to a position or a "
    "named place, patrol, walk a square, wait, do tricks (hello, dance, stretch, ...), describe "
    "what I see, report status, and stop."
)


def describe(step: SkillCall) -> str:
    """A short description of a step, for error messages."""
    a: dict[str, Any] = step.args
    if step.skill == "nav.move":
        return (
            f"move {'forward' if a['distance'] >= 0 else 'backward'} {_fmt(abs(a['distance']))} m"
        )
    if step.skill == "nav.strafe":
        return f"step {'left' if a['distance'] >= 0 else 'right'} {_fmt(abs(a['distance']))} m"
    if step.skill == "nav.rotate":
        return f"turn {'left' if a['degrees'] >= 0 else 'right'} {_fmt(abs(a['degrees']))} degrees"
    if step.skill == "nav.goto":
        if "place" in a:
            return {"start": "return to the start", "home": "go home"}.get(
                a["place"], f"go to {a['place']}"
            )
        return f"go to ({_fmt(a['x'])}, {_fmt(a['y'])})"
    if step.skill == "nav.patrol":
        return f"patrol {a['laps']} lap{'s' if a['laps'] != 1 else ''}"
    if step.skill == "body.sport":
        return f"do the {a['trick']} trick"
    if step.skill == "sys.wait":
        return f"wait {_fmt(a['seconds'])} s"
    return {
        "nav.stop": "stop", "body.stand": "stand up", "body.sit": "sit down",
        "body.lie_down": "lie down", "sys.status": "report status",
        "perception.describe": "describe what I see", "perception.look_around": "look around",
    }.get(step.skill, step.skill)  # fmt: skip


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
