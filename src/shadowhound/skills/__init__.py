"""Skills: typed robot capabilities in one registry."""

from __future__ import annotations

from . import body, memory, nav, sense
from .arguments import (
    Angle,
    AngularSpeed,
    Count,
    Duration,
    Length,
    NoArgs,
    OptionalAngle,
    OptionalAngularSpeed,
    OptionalDuration,
    OptionalLength,
    OptionalSpeed,
    SkillArgs,
    Speed,
)
from .context import MissionCancelled, PlanEnv, PlanProblem, SkillContext, SkillError, SkillTimeout
from .registry import Skill, SkillRegistry, SkillValidationError, ValidatedCall


def default_registry() -> SkillRegistry:
    """A fresh registry with every built-in skill."""
    return SkillRegistry([*nav.SKILLS, *body.SKILLS, *sense.SKILLS, *memory.SKILLS])


__all__ = [
    "Angle",
    "AngularSpeed",
    "Count",
    "Duration",
    "Length",
    "MissionCancelled",
    "NoArgs",
    "OptionalAngle",
    "OptionalAngularSpeed",
    "OptionalDuration",
    "OptionalLength",
    "OptionalSpeed",
    "PlanEnv",
    "PlanProblem",
    "Skill",
    "SkillArgs",
    "SkillContext",
    "SkillError",
    "SkillRegistry",
    "SkillTimeout",
    "SkillValidationError",
    "Speed",
    "ValidatedCall",
    "default_registry",
]
