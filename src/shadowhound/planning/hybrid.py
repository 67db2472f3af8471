"""HybridPlanner: the offline rules first, the language model for what they do not understand.

A sentence the rules understand whole ("stand up and walk forward 1 meter") is planned at no
model call, in microseconds, deterministically. Any other sentence goes to the model as the user
wrote it: the rules' partial reading is not forced on the model, so a request the rules half
understood is planned by the model from scratch. Re-planning after a failed step is the
model's (chat and image questions go to the agent's model backend, not to a planner).
React mode is not hybrid (`make_planner` gives the model's loop itself): there the model
decides each step from what the previous one observed.
"""

from __future__ import annotations

from typing import Any

from ..plan import Plan, PlanningError
from .llm import LLMPlanner
from .rules import RulePlanner


class HybridPlanner:
    """Offline rules first; the model plans only sentences the rules do not understand whole."""

    kind = "hybrid"
    needs_context = True  # the model's half reads it

    def __init__(self, offline: RulePlanner, model: LLMPlanner) -> None:
        self.offline = offline
        self.model = model
        self.name = f"hybrid:{model.name}"

    def plan(self, text: str, context: Any = None) -> Plan:
        try:
            return self.offline.plan(text)
        except PlanningError:
            pass  # not understood whole: the model plans the sentence from scratch
        return self.model.plan(text, context)

    def replan(self, text: str, context: Any, done: list[str], failure: str) -> Plan:
        return self.model.replan(text, context, done, failure)
