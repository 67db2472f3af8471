"""The e-stop lane: `POST /api/estop` stops the robot before routing, before anything else.

An ASGI layer just inside the gate (token, host, origin still apply). For the e-stop request it
calls the hard stop as the first thing its task does, with no `await` in between, so nothing the
event loop has queued after it (event fan-out, status polls, camera streams) runs first; the
route then only writes the answer. The fan-out wakes clients a slice per loop turn, each for a
batch of messages at most (feed.py), so what can be queued ahead of the e-stop is bounded too,
whatever the number of clients and however far behind they are.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .security import ASGIApp, Receive, Scope, Send

ESTOP_PATH = "/api/estop"
STATE_KEY = "estop_dropped"  # request.state: how many waiting missions the stop dropped


class EstopLane:
    """ASGI middleware: runs `estop()` (returns the number of dropped missions) for
    `POST /api/estop` before the app sees the request."""

    def __init__(self, app: ASGIApp, *, estop: Callable[[], int]) -> None:
        self.app = app
        self.estop = estop

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if (
            scope["type"] == "http"
            and scope["method"] == "POST"
            and scope.get("path") == ESTOP_PATH
        ):
            dropped = self.estop()  # first: the robot stops before anything else runs
            scope.setdefault("state", {})[STATE_KEY] = dropped
        await self.app(scope, receive, send)


def stopped_already(state: Any) -> int | None:
    """The lane's result for this request (request.state), or None when it did not run."""
    value = getattr(state, STATE_KEY, None)
    return value if isinstance(value, int) else None
