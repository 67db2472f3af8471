"""Skills: typed robot capabilities in one registry.

Each area module (nav, facing, body, sense, voice, memory) holds its skills in `SKILLS`; a skill
declares on its `Skill` everything the rest of the house needs to know of it, so a new skill
is one file.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from ..errors import MissionCancelled, PlanProblem, SkillError, SkillTimeout, SkillValidationError
from . import body, facing, follow, memory, nav, sense, voice
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

if TYPE_CHECKING:
    from ..robot.base import TrickInfo


def default_registry(tricks: Mapping[str, TrickInfo] | None = None) -> SkillRegistry:
    """A fresh registry with every built-in skill, `body.sport` offering `tricks` (a robot's
    `Robot.tricks`; none: no `body.sport`). Without `tricks`, those of the default robot (the
    simulated Go2)."""
    if tricks is None:
        from ..robot.factory import tricks_of
        from ..robot_config import SimRobotSettings

        tricks = tricks_of(SimRobotSettings())
    sport = body.sport_skill(tricks)
    return SkillRegistry(
        [
            *nav.SKILLS,
            *follow.SKILLS,
            *facing.SKILLS,
            *body.SKILLS,
            *([sport] if sport else []),
            *sense.SKILLS,
            *voice.SKILLS,
            *memory.SKILLS,
        ]
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
