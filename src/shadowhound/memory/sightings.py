"""SightingBook: the objects the robot has seen, kept for later missions.

The latest sighting of each object name (position in the odom/map frame, radius, confidence,
robot-clock stamp, wall-clock time) lives in the history database when memory is enabled (so
it survives restarts), else for the life of the process. A mission's world model (the
Belief) is seeded from it, and every new sighting is written back.

A book is one robot's (`RobotId`): it holds only what that robot saw, so a world model is never
seeded with another robot's sighting (a goal from what another robot saw).
"""

from __future__ import annotations

import logging
import math
import threading
import time
from dataclasses import dataclass

from ..robot_config import RobotId
from ..world import KnownObject
from .history import MissionHistory

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Remembered:
    """One remembered sighting; `seen_at` is wall-clock seconds (time.time())."""

    known: KnownObject
    seen_at: float


# A sighting is written again only when the object moved or the stored one grew old: the
# same object seen every mission does not rewrite the file every mission.
_MOVED = 0.05  # metres
_REFRESH = 60.0  # seconds


class SightingBook:
    """Objects `robot` saw, name -> latest sighting."""

    def __init__(self, store: MissionHistory | None = None, *, robot: RobotId) -> None:
        self._store = store
        self.robot = robot
        self._lock = threading.Lock()
        self._seen: dict[str, Remembered] = {}
        if store is not None:
            for name, x, y, radius, confidence, stamp, seen_at in store.load_sightings(robot):
                try:
                    known = KnownObject(name, x, y, radius, confidence, stamp, remembered=True)
                except (TypeError, ValueError) as exc:  # a row no sighting could have made
                    log.warning("skipped the sighting of %r read from the history: %s", name, exc)
                    continue
                self._seen[name] = Remembered(known, seen_at)

    def remember(self, known: KnownObject) -> None:
        now = time.time()
        with self._lock:
            old = self._seen.get(known.name)
            fresh = (
                old is not None
                and now - old.seen_at < _REFRESH
                and math.hypot(old.known.x - known.x, old.known.y - known.y) < _MOVED
            )
            self._seen[known.name] = Remembered(known, old.seen_at if fresh and old else now)
        if self._store is not None and not fresh:
            self._store.save_sighting(
                self.robot,
                known.name,
                known.x,
                known.y,
                known.radius,
                known.confidence,
                known.stamp,
            )

    def all(self) -> list[Remembered]:
        with self._lock:
            return sorted(self._seen.values(), key=lambda r: r.known.name)
