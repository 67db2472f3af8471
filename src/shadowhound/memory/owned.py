"""The places and sightings of the history database: every row is its robot's.

`MissionHistory` keeps them in the same file as the missions (this is its part for them). Goals
are read only with a robot: `load_places(robot)` and `load_sightings(robot)` return that robot's
own rows and nothing else, so no caller can take another robot's memory (or one of no known
robot, from before robots were recorded) for a goal. `every_place` and `every_sighting` are
every robot's, labelled (records.py): history for listings, never goals.
"""

from __future__ import annotations

import sqlite3
import threading
import time
from typing import Any

from ..errors import MemoryStoreError
from ..robot_config import RobotId
from . import claims
from .records import StoredPlace, StoredSighting


class PlacesAndSightings:
    """MissionHistory's places and sightings (it provides the connection and the writes)."""

    _db: sqlite3.Connection
    _lock: threading.Lock

    def _write(self, what: str, sql: str, params: tuple[Any, ...]) -> None:
        raise NotImplementedError

    def _flush(self) -> None:
        raise NotImplementedError

    def _query(self, sql: str, params: tuple[Any, ...]) -> list[tuple[Any, ...]]:
        raise NotImplementedError

    def _failed(self, exc: sqlite3.DatabaseError) -> MemoryStoreError:
        raise NotImplementedError

    def save_place(self, robot: RobotId, name: str, x: float, y: float, yaw: float) -> None:
        self._write(
            f"place {name!r}",
            "INSERT OR REPLACE INTO places (robot_id, name, x, y, yaw, created_at) "
            "VALUES (?, ?, ?, ?, ?, ?)",
            (robot.name, name, x, y, yaw, time.time()),
        )

    def delete_place(self, robot: RobotId, name: str) -> None:
        self._write(
            f"forgetting the place {name!r}",
            "DELETE FROM places WHERE robot_id = ? AND name = ?",
            (robot.name, name),
        )

    def load_places(self, robot: RobotId) -> dict[str, tuple[float, float, float]]:
        """The places `robot` was taught (never another's, nor one of no known robot)."""
        rows = self._query(
            "SELECT name, x, y, yaw FROM places WHERE robot_id = ? ORDER BY name", (robot.name,)
        )
        return {name: (x, y, yaw) for name, x, y, yaw in rows}

    def save_sighting(
        self,
        robot: RobotId,
        name: str,
        x: float,
        y: float,
        radius: float,
        confidence: float,
        stamp: float,
    ) -> None:
        """The latest sighting of `name` by `robot` (replaces that robot's older one)."""
        self._write(
            f"sighting of {name!r}",
            "INSERT OR REPLACE INTO sightings (robot_id, name, x, y, radius, confidence, "
            "stamp, seen_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
            (robot.name, name, x, y, radius, confidence, stamp, time.time()),
        )

    def load_sightings(
        self, robot: RobotId
    ) -> list[tuple[str, float, float, float, float, float, float]]:
        """What `robot` saw: (name, x, y, radius, confidence, robot stamp, wall-clock
        seen_at), by name (never another robot's, nor one of no known robot)."""
        return [
            tuple(r)
            for r in self._query(
                "SELECT name, x, y, radius, confidence, stamp, seen_at FROM sightings "
                "WHERE robot_id = ? ORDER BY name",
                (robot.name,),
            )
        ]

    def every_place(self) -> list[StoredPlace]:
        """Every robot's taught places, labelled with their robot: history, for listings."""
        rows = self._query(
            "SELECT robot_id, name, x, y, yaw, created_at FROM places ORDER BY name, robot_id", ()
        )
        return [StoredPlace(*row) for row in rows]

    def every_sighting(self) -> list[StoredSighting]:
        """Every robot's latest sightings, labelled with their robot: history, for listings."""
        rows = self._query(
            "SELECT robot_id, name, x, y, radius, confidence, stamp, seen_at FROM sightings "
            "ORDER BY name, robot_id",
            (),
        )
        return [StoredSighting(*row) for row in rows]

    def claim(self, robot: RobotId, name: str) -> list[str]:
        """Make the place and the sighting called `name` that belong to no known robot (from
        before robots were recorded) `robot`'s own: a person vouches that this robot made
        them. Returns what was claimed ("place", "sighting"). Raises ClaimError when there is
        nothing of no known robot by that name, or `robot` already has its own."""
        with self._lock:
            self._flush()
            try:
                return claims.claim(self._db, robot, name)
            except sqlite3.DatabaseError as exc:
                raise self._failed(exc) from exc
