"""Skills: typed robot capabilities in one registry.

Each area module (nav, facing, body, sense, voice, memory) holds its skills in `SKILLS`; a skill
declares on its `Skill` everything the rest of the house needs to know of it, so a new skill
is one file.
"""

from __future__ import annotations

from ..errors import MissionCancelled, PlanProblem, SkillError, SkillTimeout, SkillValidationError
from . import body, facing, memory, nav, sense, voice
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
from .context import PlanEnv, SkillContext
from .registry import Skill, SkillRegistry, ValidatedCall


def default_registry() -> SkillRegistry:
    """A fresh registry with every built-in skill."""
    return SkillRegistry(
        [*nav.SKILLS, *facing.SKILLS, *body.SKILLS, *sense.SKILLS, *voice.SKILLS, *memory.SKILLS]
    )


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
