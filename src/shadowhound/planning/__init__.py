"""Planners turn text into a `Plan`. They never touch the robot.

Three declared protocols say what the agent may use of a planner: every `Planner` plans a
whole mission; a `ReplanningPlanner` can also plan the rest of one after a step failed; a
`StepwisePlanner` (react mode) proposes one skill call at a time and sees each result.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Collection
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from ..config import ShadowHoundConfig
from ..plan import Plan, SkillCall, Usage
from ._phrases import TRAVEL as TRAVEL_QUESTION  # chat answers the same questions

if TYPE_CHECKING:
    from ..llm.backend import LLMBackend
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

    `needs_context` False says the planner ignores the PlanningContext; it then gets None and
    the agent spends nothing on building one. `kind` (offline | llm | hybrid | explicit) is
    what `MissionResult.planner` records.
    """

    name: str
    kind: str
    needs_context: bool

    def plan(self, text: str, context: Any = None) -> Plan: ...


@runtime_checkable
class ReplanningPlanner(Planner, Protocol):
    """A planner that can plan the rest of a mission after a step failed."""

    def replan(self, text: str, context: Any, done: list[str], failure: str) -> Plan:
        """The remaining steps from where the robot is now; `done` are the finished steps'
        outputs, `failure` what went wrong."""
        ...


StepRunner = Callable[[SkillCall], str]  # runs one proposed call; returns the observation


@runtime_checkable
class StepwisePlanner(Planner, Protocol):
    """A planner that proposes one skill call at a time (react mode): `run_step` checks and
    runs each and returns what happened."""

    def react(self, text: str, context: Any, run_step: StepRunner) -> tuple[str, Usage, bool]:
        """Returns (the answer for the user, usage, finished normally)."""
        ...


class FixedPlanner:
    """Returns a plan given in advance (explicit skill calls from an API, a script or a test)."""

    name = "explicit"
    kind = "explicit"
    needs_context = False

    def __init__(self, plan: Plan) -> None:
        self._plan = plan

    def plan(self, text: str, context: Any = None) -> Plan:
        return self._plan


def make_planner(
    settings: ShadowHoundConfig,
    backend: LLMBackend | None = None,
    *,
    tricks: Collection[str] | None = None,
) -> Planner:
    """The planner for `settings`: the offline rules, or a language model behind them.

    With a model configured, plan mode is hybrid unless `llm.hybrid` is off: the offline rules
    plan what they understand whole, at no model call, and the model plans the rest. React
    mode is the model's loop from the first step. `backend` is the one client of the model
    (the agent builds it once and shares it with chat, vision and memory). `tricks`: the
    names of the robot's tricks (None: every trick the offline rules have words for).
    """
    from .rules import RulePlanner

    if settings.backend == "offline":
        return RulePlanner(tricks=tricks)
    from .llm import LLMPlanner, ReactPlanner

    if settings.llm.mode == "react":
        return ReactPlanner(settings, backend)
    model = LLMPlanner(settings, backend)
    if settings.llm.hybrid:
        from .hybrid import HybridPlanner

        return HybridPlanner(RulePlanner(tricks=tricks), model)
    return model


__all__ = [
    "FixedPlanner",
    "Planner",
    "PlanningContext",
    "ReplanningPlanner",
    "StepRunner",
    "StepwisePlanner",
    "TRAVEL_QUESTION",
    "make_planner",
]
