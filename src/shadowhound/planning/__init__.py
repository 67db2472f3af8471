"""Planners turn text into a `Plan`. They never touch the robot."""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from ..config import ShadowHoundConfig
from ..plan import Plan

if TYPE_CHECKING:
    from ..skills import SkillRegistry
    from ..state import RobotState


@dataclass
class PlanningContext:
    """What a planner may know: the skills, the robot now, places, objects seen, and recent
    missions."""

    registry: SkillRegistry
    state: RobotState | None = None
    places: dict[str, tuple[float, float]] = field(default_factory=dict)
    history: list[str] = field(default_factory=list)
    cancelled: threading.Event | None = None
    memories: list[str] = field(default_factory=list)  # relevant memories, bounded
    objects: dict[str, tuple[float, float]] = field(default_factory=dict)  # seen, odom frame


@runtime_checkable
class Planner(Protocol):
    """Turns a request into a Plan, or raises PlanningError saying what it did not understand.

    A planner may set `needs_context = False` when it ignores the PlanningContext; it then gets
    None and the agent spends nothing on building one. `kind` (offline | llm | hybrid |
    explicit) is what `MissionResult.planner` records; a planner without one records "".
    """

    name: str

    def plan(self, text: str, context: Any = None) -> Plan: ...


class FixedPlanner:
    """Returns a plan given in advance (explicit skill calls from an API, a script or a test)."""

    name = "explicit"
    kind = "explicit"
    needs_context = False

    def __init__(self, plan: Plan) -> None:
        self._plan = plan

    def plan(self, text: str, context: Any = None) -> Plan:
        return self._plan


def make_planner(settings: ShadowHoundConfig) -> Planner:
    """The planner for `settings`: the offline rules, or a language model behind them.

    With a model configured, plan mode is hybrid unless `llm.hybrid` is off: the offline rules
    plan what they understand whole, at no model call, and the model plans the rest. React
    mode is the model's loop from the first step.
    """
    from .rules import RulePlanner

    if settings.backend == "offline":
        return RulePlanner()
    from .llm import LLMPlanner

    model = LLMPlanner(settings)
    if settings.llm.hybrid and settings.llm.mode == "plan":
        from .hybrid import HybridPlanner

        return HybridPlanner(RulePlanner(), model)
    return model


__all__ = ["FixedPlanner", "Planner", "PlanningContext", "make_planner"]
