"""Plans: what a planner proposes. Nothing here touches the robot."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .errors import PlanningError as PlanningError


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
class Usage:
    """Language-model cost of a mission. All zero for the offline planner."""

    prompt_tokens: int = 0
    completion_tokens: int = 0
    round_trips: int = 0
    estimated: bool = False  # True when the server reported no usage and tokens were counted
    invalid_plans: int = 0  # model replies that failed validation (each one goes to repair)

    @property
    def total_tokens(self) -> int:
        return self.prompt_tokens + self.completion_tokens

    def add(self, other: Usage) -> None:
        self.prompt_tokens += other.prompt_tokens
        self.completion_tokens += other.completion_tokens
        self.round_trips += other.round_trips
        self.estimated = self.estimated or other.estimated
        self.invalid_plans += other.invalid_plans

    def to_dict(self) -> dict[str, Any]:
        return {
            "prompt_tokens": self.prompt_tokens,
            "completion_tokens": self.completion_tokens,
            "total_tokens": self.total_tokens,
            "round_trips": self.round_trips,
            "estimated": self.estimated,
            "invalid_plans": self.invalid_plans,
        }


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
