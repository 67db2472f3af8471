"""How many MCP sessions may be open over HTTP, and how long an idle one lives (`sessions.py`
enforces them). No SDK here: the command line reads the defaults for its help."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ServeError

__all__ = ["DEFAULT_IDLE_TIMEOUT", "DEFAULT_MAX_SESSIONS", "SessionLimits"]

DEFAULT_IDLE_TIMEOUT = 300.0  # seconds: a client that stays connected never goes idle
DEFAULT_MAX_SESSIONS = 32  # an idle session costs ~40 KB; a robot has a few clients


@dataclass(frozen=True)
class SessionLimits:
    """How long an idle session lives (seconds) and how many sessions may be open."""

    idle_timeout: float = DEFAULT_IDLE_TIMEOUT
    max_sessions: int = DEFAULT_MAX_SESSIONS

    def __post_init__(self) -> None:
        idle = self.idle_timeout
        number = isinstance(idle, (int, float)) and not isinstance(idle, bool)
        if not number or not math.isfinite(idle) or idle <= 0:
            raise ServeError(
                "the session idle time-out (--session-idle) must be a number of seconds "
                f"above 0, got {idle!r}"
            )
        count = self.max_sessions
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise ServeError(
                "the session limit (--max-sessions) must be a whole number of at least 1, "
                f"got {count!r}"
            )
