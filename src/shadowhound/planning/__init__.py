"""Planners turn text into a `Plan`. They never touch the robot."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from ..config import ConfigError, ShadowHoundConfig
from ..plan import Plan


@runtime_checkable
class Planner(Protocol):
    """Turns a request into a Plan, or raises PlanningError saying what it did not understand."""

    name: str

    def plan(self, text: str, context: Any = None) -> Plan: ...


class FixedPlanner:
    """Returns a plan given in advance (explicit skill calls from an API, a script or a test)."""

    name = "explicit"

    def __init__(self, plan: Plan) -> None:
        self._plan = plan

    def plan(self, text: str, context: Any = None) -> Plan:
        return self._plan


def make_planner(settings: ShadowHoundConfig) -> Planner:
    """The planner for `settings.backend`."""
    if settings.backend == "offline":
        from .rules import RulePlanner

        return RulePlanner()
    raise ConfigError(
        f"backend {settings.backend!r} is not available in this version of ShadowHound; "
        "language-model planning is not implemented yet. Use backend 'offline'."
    )


__all__ = ["FixedPlanner", "Planner", "make_planner"]
