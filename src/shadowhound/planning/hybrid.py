"""HybridPlanner: the offline rules first, the language model for what they do not understand.

A sentence the rules understand whole ("stand up and walk forward 1 meter") is planned at no
model call, in microseconds, deterministically. Any other sentence goes to the model as the user
wrote it: the rules' partial reading is not forced on the model, so a request the rules half
understood is planned by the model from scratch. Re-planning after a failed step, chat and
image questions are the model's. React mode is not hybrid (`make_planner` gives the model's
loop itself): there the model decides each step from what the previous one observed.
"""

from __future__ import annotations

from typing import Any

from ..plan import Plan, PlanningError
from ..state import CameraFrame
from .llm import LLMPlanner
from .rules import RulePlanner


class HybridPlanner:
    """Offline rules first; the model plans only sentences the rules do not understand whole."""

    kind = "hybrid"
    mode = "plan"

    def __init__(self, offline: RulePlanner, model: LLMPlanner) -> None:
        self.offline = offline
        self.model = model
        self.name = f"hybrid:{model.name}"

    @property
    def backend(self) -> Any:
        """The model's backend (the agent's memory embeds through it)."""
        return self.model.backend

    def check(self) -> list[str]:
        return self.model.check()

    def plan(self, text: str, context: Any = None) -> Plan:
        try:
            return self.offline.plan(text)
        except PlanningError:
            pass  # not understood whole: the model plans the sentence from scratch
        return self.model.plan(text, context)

    def replan(self, text: str, context: Any, done: list[str], failure: str) -> Plan:
        return self.model.replan(text, context, done, failure)

    def chat(self, text: str, context: Any, history: list[dict[str, str]]) -> str:
        return self.model.chat(text, context, history)

    def describe_image(self, frame: CameraFrame, question: str) -> str:
        return self.model.describe_image(frame, question)
