"""Plans: what a planner proposes. Nothing here touches the robot."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .errors import PlanningError as PlanningError
from .usage import Usage as Usage


@dataclass(frozen=True)
class SkillCall:
    """One proposed step: a registered skill name and its (not yet validated) arguments."""

    skill: str
    args: dict[str, Any] = field(default_factory=dict)
    label: str = ""  # the words of the request this step came from, for people

    def to_dict(self) -> dict[str, Any]:
        # A language model may propose anything; keep the record JSON-safe whatever it is.
        args = dict(self.args) if isinstance(self.args, dict) else {"_invalid": repr(self.args)}
        return {"skill": self.skill, "args": args, "label": self.label}


@dataclass
class Plan:
    """An ordered list of skill calls for one request, plus what the planner assumed."""

    steps: list[SkillCall]
    text: str = ""
    notes: list[str] = field(default_factory=list)  # assumptions, e.g. "no distance given: 1 m"
    usage: Usage = field(default_factory=Usage)
    planner: str = ""  # the planner's name, e.g. "offline" or "llamacpp:qwen2.5"
    planned_by: str = ""  # offline | llm | explicit: the kind of planner that made it

    def to_dict(self) -> dict[str, Any]:
        return {
            "text": self.text,
            "planner": self.planner,
            "planned_by": self.planned_by,
            "steps": [s.to_dict() for s in self.steps],
            "notes": list(self.notes),
        }
