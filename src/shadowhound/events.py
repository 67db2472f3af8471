"""Mission events that interfaces (CLI progress, web, ROS, MCP, memory) subscribe to.

Each kind of event is its own frozen dataclass carrying typed records (a `StepResult`, a
`Plan`, a `MissionResult`), copied when the event is made, so a listener that reads it later
sees the mission as it was then. Listeners choose events by type (`isinstance(event,
StepFinished)`). `data` / `to_dict()` are the JSON form, for the edges only (web feed, MCP
progress, tests that print); it is built once per event, on first use.
"""

from __future__ import annotations

import copy
import logging
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

if TYPE_CHECKING:
    from .approval import ApprovalRequest
    from .plan import Plan
    from .result import MissionResult, StepResult

log = logging.getLogger(__name__)
_Step = TypeVar("_Step", bound="_StepEvent")

MISSION_STARTED = "mission_started"
PLAN_READY = "plan_ready"
STEP_STARTED = "step_started"
STEP_FINISHED = "step_finished"
MISSION_FINISHED = "mission_finished"
ESTOP = "estop"
APPROVAL_REQUIRED = "approval_required"
APPROVAL_DECIDED = "approval_decided"
SPOKEN = "spoken"
WATCH_FIRED = "watch_fired"


@dataclass(frozen=True)
class MissionEvent:
    """The common part: which mission (`""` when none runs) and when. `kind` names the type
    on the wire (one of the constants above)."""

    kind: ClassVar[str] = ""
    mission_id: str
    time: float = field(default_factory=time.time, kw_only=True)

    def payload(self) -> dict[str, Any]:
        """The event's own fields as JSON-ready values."""
        return {}

    @cached_property
    def data(self) -> dict[str, Any]:
        """JSON form of the payload (for the edges), converted once."""
        return self.payload()

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "mission_id": self.mission_id, "time": self.time, **self.data}


@dataclass(frozen=True)
class MissionStarted(MissionEvent):
    kind: ClassVar[str] = MISSION_STARTED
    mission: str

    def payload(self) -> dict[str, Any]:
        return {"mission": self.mission}


@dataclass(frozen=True)
class PlanReady(MissionEvent):
    """The checked plan is about to run (a copy: a re-plan later adds steps to the original)."""

    kind: ClassVar[str] = PLAN_READY
    plan: Plan
    path: tuple[tuple[float, float], ...] = ()  # the checked predicted path (maps, RViz)

    @classmethod
    def of(cls, mission_id: str, plan: Plan, path: Iterable[tuple[float, float]] = ()) -> PlanReady:
        return cls(mission_id, copy.deepcopy(plan), tuple(path))

    def payload(self) -> dict[str, Any]:
        return {
            "plan": self.plan.to_dict(),
            "path": [{"x": round(x, 4), "y": round(y, 4)} for x, y in self.path],
        }


@dataclass(frozen=True)
class _StepEvent(MissionEvent):
    step: StepResult

    @classmethod
    def of(cls: type[_Step], mission_id: str, step: StepResult) -> _Step:
        return cls(mission_id, replace(step))  # the step as it is now

    def payload(self) -> dict[str, Any]:
        return {"step": self.step.to_dict()}


@dataclass(frozen=True)
class StepStarted(_StepEvent):
    kind: ClassVar[str] = STEP_STARTED


@dataclass(frozen=True)
class StepFinished(_StepEvent):
    kind: ClassVar[str] = STEP_FINISHED


@dataclass(frozen=True)
class MissionFinished(MissionEvent):
    kind: ClassVar[str] = MISSION_FINISHED
    result: MissionResult

    def payload(self) -> dict[str, Any]:
        return {"result": self.result.to_dict()}


@dataclass(frozen=True)
class EstopChanged(MissionEvent):
    """The e-stop was pressed (`latched`) or released."""

    kind: ClassVar[str] = ESTOP
    latched: bool

    def payload(self) -> dict[str, Any]:
        return {"latched": self.latched}


@dataclass(frozen=True)
class ApprovalRequired(MissionEvent):
    kind: ClassVar[str] = APPROVAL_REQUIRED
    request: ApprovalRequest

    def payload(self) -> dict[str, Any]:
        return {"request": self.request.to_dict()}


@dataclass(frozen=True)
class ApprovalDecided(MissionEvent):
    kind: ClassVar[str] = APPROVAL_DECIDED
    approved: bool
    reason: str | None

    def payload(self) -> dict[str, Any]:
        return {"approved": self.approved, "reason": self.reason}


@dataclass(frozen=True)
class Spoken(MissionEvent):
    """A step said words (`voice.say`): spoken aloud, or not (`why_silent`: over the rate, no
    voice on this robot). Dashboards show the words either way."""

    kind: ClassVar[str] = SPOKEN
    text: str
    step: int  # the step's index in the mission
    why_silent: str = ""

    @property
    def aloud(self) -> bool:
        return not self.why_silent

    def payload(self) -> dict[str, Any]:
        return {
            "text": self.text,
            "step": self.step,
            "aloud": self.aloud,
            "why_silent": self.why_silent,
        }


@dataclass(frozen=True)
class WatchFiredEvent(MissionEvent):
    """A step's watched condition held and stopped it (`text`: "stopped: red ball seen 2.3 m
    away (until red ball is seen)"); the step's record says the same."""

    kind: ClassVar[str] = WATCH_FIRED
    step: int  # the step's index in the mission
    text: str

    def payload(self) -> dict[str, Any]:
        return {"step": self.step, "text": self.text}


Listener = Callable[[MissionEvent], None]


class EventBus:
    """Calls every listener in the emitting thread. A failing listener is logged, not fatal."""

    def __init__(self) -> None:
        self._listeners: list[Listener] = []
        self._lock = threading.Lock()

    def subscribe(self, listener: Listener) -> Callable[[], None]:
        with self._lock:
            self._listeners.append(listener)

        def unsubscribe() -> None:
            with self._lock:
                if listener in self._listeners:
                    self._listeners.remove(listener)

        return unsubscribe

    def emit(self, event: MissionEvent) -> None:
        with self._lock:
            listeners = list(self._listeners)
        for listener in listeners:
            try:
                listener(event)
            except Exception:  # a broken display must never break a mission
                log.exception("event listener %r failed on %s", listener, event.kind)
