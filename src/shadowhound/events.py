"""Mission events that interfaces (CLI progress, web, ROS) subscribe to."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

log = logging.getLogger(__name__)

MISSION_STARTED = "mission_started"
PLAN_READY = "plan_ready"
STEP_STARTED = "step_started"
STEP_FINISHED = "step_finished"
MISSION_FINISHED = "mission_finished"
ESTOP = "estop"
APPROVAL_REQUIRED = "approval_required"
APPROVAL_DECIDED = "approval_decided"


@dataclass(frozen=True)
class MissionEvent:
    """`kind` is one of the constants above; `data` is JSON-ready."""

    kind: str
    mission_id: str
    data: dict[str, Any] = field(default_factory=dict)
    time: float = field(default_factory=time.time)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "mission_id": self.mission_id, "time": self.time, **self.data}


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
