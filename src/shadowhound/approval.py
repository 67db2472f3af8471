"""Approvals: a plan with risky steps (or any plan, with `require_approval`) waits here until an
interface approves or rejects it, the time-out passes, or the mission is cancelled.

Interfaces that can ask a person (the CLI prompt, the web page, a ROS service) call
`RobotAgent.enable_approvals()`; without one, plans that need approval are refused at once.
"""

from __future__ import annotations

import threading
import time
import uuid
from dataclasses import dataclass, field
from typing import Any


@dataclass
class ApprovalRequest:
    """A plan waiting for a person. `reasons` say why approval is needed."""

    mission_id: str
    mission: str
    steps: list[dict[str, Any]]
    reasons: list[str]
    timeout: float
    request_id: str = field(default_factory=lambda: uuid.uuid4().hex[:8])
    created: float = field(default_factory=time.time)
    approved: bool | None = None
    note: str = ""
    _decided: threading.Event = field(default_factory=threading.Event, repr=False)

    def to_dict(self) -> dict[str, Any]:
        return {
            "request_id": self.request_id,
            "mission_id": self.mission_id,
            "mission": self.mission,
            "steps": self.steps,
            "reasons": self.reasons,
            "timeout": self.timeout,
            "expires_at": self.created + self.timeout,
        }


class ApprovalDesk:
    """Holds at most one pending request (one mission runs at a time)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pending: ApprovalRequest | None = None
        self.enabled = False  # an interface that can ask a person is attached

    def open(self, request: ApprovalRequest) -> None:
        """Make `request` the pending one, before anyone is told about it."""
        with self._lock:
            self._pending = request

    def wait(self, request: ApprovalRequest, cancelled: threading.Event) -> str | None:
        """Block until decided (or cancelled, or timed out), then close the request.

        Returns None when approved, else why not.
        """
        try:
            deadline = time.monotonic() + request.timeout
            while not request._decided.wait(0.05):
                if cancelled.is_set():
                    return "cancelled while waiting for approval"
                if time.monotonic() > deadline:
                    return f"no approval within {request.timeout:g} s (safety.approval_timeout)"
            if request.approved:
                return None
            return "rejected" + (f": {request.note}" if request.note else "")
        finally:
            with self._lock:
                self._pending = None

    def decide(self, approved: bool, request_id: str | None = None, note: str = "") -> bool:
        """Approve or reject the pending request (or the one with `request_id`).

        Returns False when there is no such pending request.
        """
        with self._lock:
            request = self._pending
            if request is None or (
                request_id is not None
                and request_id not in (request.request_id, request.mission_id)
            ):
                return False
            request.approved, request.note = approved, note
            request._decided.set()
            return True

    def pending(self) -> ApprovalRequest | None:
        with self._lock:
            return self._pending
