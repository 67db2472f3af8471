"""The `Logbook`: the missions one agent ran, as its history listing, diagnostics, prompts and
chat read them.

Every result is kept in the process (the latest `agent.conversation_history_size`); with
memory enabled the history database holds them too and is read first, so a listing survives
restarts.
"""

from __future__ import annotations

from collections import deque
from typing import Any

from .memory.service import AgentMemory
from .result import MissionResult


class Logbook:
    """The missions of one agent: this process's results, and the memory's history database
    when there is one. `size` is how many missions prompts and chat are told about."""

    def __init__(self, memory: AgentMemory, size: int) -> None:
        self.memory = memory
        self.size = size
        self._results: deque[MissionResult] = deque(maxlen=max(1, size))

    def add(self, result: MissionResult) -> None:
        self._results.append(result)

    def results(self) -> list[MissionResult]:
        """This process's latest results, oldest first."""
        return list(self._results)

    def last(self) -> MissionResult | None:
        return self._results[-1] if self._results else None

    def recent(self, limit: int = 10) -> list[dict[str, Any]]:
        """This robot's missions, newest first: id, mission, status, success, response,
        started_at, finished_at, robot_id. From the history database when memory is enabled (so
        it survives restarts), else from this process."""
        rows = self.memory.recent_missions(limit)
        if rows or self.memory.history is not None:
            return rows
        robot = {"robot_id": self.memory.robot.name}  # the database's shape: whose mission
        return [{**r.history_row(), **robot} for r in reversed(self._results)][:limit]

    def summaries(self, *, finished_only: bool = False) -> list[str]:
        """The latest `size` missions, oldest first, one line each (for prompts and chat).
        `finished_only` leaves out the running one: a planner is planning it, it is the
        request rather than a recent mission."""
        rows = self.recent(self.size + finished_only)
        if finished_only:
            rows = [r for r in rows if r.get("status") != "running"][: self.size]
        return [f"{r['status']}: {r['mission']!r} -> {r['response']}" for r in reversed(rows)]
