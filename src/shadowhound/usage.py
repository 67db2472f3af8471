"""What a mission cost in language-model tokens and round trips (all zero offline).

Its own module at the base, so the error tree (a PlanningError carries what the failed attempt
cost) and plans can both hold it without importing each other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


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
