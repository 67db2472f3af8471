"""MissionHistory: every mission, its plan, steps, timing, result and refusals, in SQLite.

One file (`history.db` in the data directory), WAL mode so the web and ROS threads and other
processes can read while one writes. A mission is written when an interface accepts it into
its queue (status `queued`), when it starts (`running`) and when it finishes; one that was
accepted but never started is `not_run`, with the reason. Each queued or running row names the
process that owns it (a lease, see lease.py); when any process opens the file, rows whose owner
has ended are marked: `running` ones `interrupted`, `queued` ones `not_run`. A live owner's
missions are never touched by another process. A write that fails for now (the file is locked
past the busy time-out, the disk is full) is kept in memory and retried, in order, with the
next write, so no record is lost while the process lives. A record the database refuses for
good (a constraint it breaks, a value SQLite cannot hold) is set aside instead, as one line
of strict JSON with the error in `history.rejected.jsonl` beside the database, so the records
after it still land (backlog.py).

Every mission, taught place and sighting carries the robot that made it (`RobotId`); places and
sightings are read as goals only by their robot (owned.py). A file from before robots were
recorded is migrated in place when opened (schema.py).
"""

from __future__ import annotations

import json
import logging
import sqlite3
import threading
import time
from pathlib import Path
from typing import Any

from .. import jsonout
from ..errors import MemoryStoreError
from ..robot_config import RobotId
from . import schema
from .backlog import Backlog, Write
from .lease import Lease, live_owners
from .owned import PlacesAndSightings

log = logging.getLogger(__name__)

# What a mission's row says, in `recent` and `get`.
_LISTED = (
    "id",
    "mission",
    "status",
    "success",
    "response",
    "started_at",
    "finished_at",
    "robot_id",
)
INTERRUPTED = "interrupted: the process running it ended before it finished"
NEVER_STARTED = "not run: the process that accepted it ended before its turn"


class MissionHistory(PlacesAndSightings):
    """Thread-safe access to the history database at `path`."""

    def __init__(self, path: str | Path, *, busy_timeout: float = 5.0) -> None:
        self.path = Path(path).expanduser()
        self._owners = self.path.with_name(self.path.name + "-owners")  # lease files
        self._lease: Lease | None = None
        self._lock = threading.Lock()
        self._backlog = Backlog(self.path.with_suffix(".rejected.jsonl"))
        self._closed = False
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._db = sqlite3.connect(
                str(self.path), timeout=busy_timeout, check_same_thread=False, isolation_level=None
            )
            self._db.execute(f"PRAGMA busy_timeout = {int(busy_timeout * 1000)}")
            self._db.execute("PRAGMA journal_mode = WAL")
            # In WAL mode NORMAL never corrupts the file and survives a crashed process; only a
            # power cut may drop the last commits. FULL would fsync every mission (slower).
            self._db.execute("PRAGMA synchronous = NORMAL")
            schema.prepare(self._db)
            self.interrupted, self.not_run = self._mark_ownerless()
            if self.not_run:
                log.warning(
                    "%d mission(s) were waiting in the queue when their process ended; "
                    "marked not_run",
                    self.not_run,
                )
        except sqlite3.DatabaseError as exc:
            raise MemoryStoreError(_explain(self.path, exc)) from exc
        except OSError as exc:
            raise MemoryStoreError(
                f"cannot open the history database {str(self.path)!r}: {exc}; check memory.data_dir"
            ) from exc

    def close(self) -> None:
        with self._lock:
            self._flush()
            self._db.close()
            self._closed = True
            if self._lease is not None:
                self._lease.release()
                self._lease = None

    def _mark_ownerless(self) -> tuple[int, int]:
        """Mark the queued and running missions of ended processes. Returns how many of each."""
        live = sorted(live_owners(self._owners))
        dead = f"owner IS NULL OR owner NOT IN ({', '.join('?' * len(live))})"  # () is fine
        now = time.time()
        interrupted = self._db.execute(
            f"UPDATE missions SET status = 'interrupted', success = 0, finished_at = ?, "
            f"response = ? "
            f"WHERE status = 'running' AND ({dead})",
            (now, INTERRUPTED, *live),
        ).rowcount
        not_run = self._db.execute(
            f"UPDATE missions SET status = 'not_run', success = 0, finished_at = ?, "
            f"response = ? WHERE status = 'queued' AND ({dead})",
            (now, NEVER_STARTED, *live),
        ).rowcount
        return interrupted, not_run

    def _owner(self) -> str | None:
        """This process's lease token, taken on first use (readers never take one)."""
        with self._lock:
            if self._lease is None:
                try:
                    self._lease = Lease(self._owners)
                except OSError as exc:  # the row is still written; others may mark it
                    log.error(
                        "cannot take a lease in %s (%s): missions of this process may "
                        "be marked interrupted by others",
                        self._owners,
                        exc,
                    )
                    return None
            return self._lease.token

    # -- writing ----------------------------------------------------------------------------

    # Every write names the robot (`RobotId`) whose mission, place or sighting it is.

    def mission_queued(
        self, mission_id: str, mission: str, queued_at: float, *, robot: RobotId
    ) -> None:
        """An interface accepted the mission; it waits for its turn."""
        self._write(
            f"queued mission {mission_id}",
            "INSERT OR REPLACE INTO missions (id, mission, status, started_at, owner, robot_id) "
            "VALUES (?, ?, 'queued', ?, ?, ?)",
            (mission_id, mission, queued_at, self._owner(), robot.name),
        )

    def mission_started(
        self, mission_id: str, mission: str, started_at: float, *, robot: RobotId
    ) -> None:
        self._write(
            f"started mission {mission_id}",
            "INSERT OR REPLACE INTO missions (id, mission, status, started_at, owner, robot_id) "
            "VALUES (?, ?, 'running', ?, ?, ?)",
            (mission_id, mission, started_at, self._owner(), robot.name),
        )

    def mission_not_run(
        self, mission_id: str, mission: str, reason: str, finished_at: float, *, robot: RobotId
    ) -> None:
        """A mission that was accepted but never started (dropped, cancelled, refused)."""
        self._write(
            f"mission {mission_id} not run",
            "INSERT INTO missions (id, mission, status, success, response, started_at, "
            "finished_at, robot_id) VALUES (?, ?, 'not_run', 0, ?, ?, ?, ?) "
            "ON CONFLICT(id) DO UPDATE SET status = 'not_run', success = 0, "
            "response = excluded.response, finished_at = excluded.finished_at",
            (mission_id, mission, reason, finished_at, finished_at, robot.name),
        )

    def mission_finished(
        self, record: dict[str, Any], finished_at: float, *, robot: RobotId
    ) -> None:
        """Store a finished mission (`MissionResult.to_dict()`), also one that never started.
        The record is kept as strict JSON (a number that is not finite is null)."""
        mission_id = record.get("mission_id")
        try:
            params = (
                mission_id,
                record["mission"],
                record["status"],
                int(record["success"]),
                record["response"],
                finished_at - record["timing"]["total_duration"],
                finished_at,
                jsonout.dumps(record, default=str),
                robot.name,
            )
        except (KeyError, TypeError, ValueError) as exc:  # not a result's record
            with self._lock:
                self._backlog.set_aside(Write(f"finished mission {mission_id}", "", (record,)), exc)
            return
        self._write(
            f"finished mission {mission_id}",
            "INSERT INTO missions (id, mission, status, success, response, started_at, "
            "finished_at, record, robot_id) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?) "
            "ON CONFLICT(id) DO UPDATE SET status = excluded.status, success = excluded.success, "
            "response = excluded.response, finished_at = excluded.finished_at, "
            "record = excluded.record",
            params,
        )

    def prune(self, *, max_age_days: float | None, max_missions: int | None) -> int:
        """Delete old missions. Returns how many were deleted."""
        deleted = 0
        with self._lock:
            try:
                if max_age_days is not None:
                    cutoff = time.time() - max_age_days * 86400
                    deleted += self._db.execute(
                        "DELETE FROM missions WHERE started_at < ?", (cutoff,)
                    ).rowcount
                if max_missions is not None:
                    deleted += self._db.execute(
                        "DELETE FROM missions WHERE id NOT IN (SELECT id FROM missions "
                        "ORDER BY started_at DESC LIMIT ?)",
                        (max_missions,),
                    ).rowcount
            except sqlite3.DatabaseError as exc:
                log.error("pruning the mission history failed: %s", _explain(self.path, exc))
        return deleted

    def _write(self, what: str, sql: str, params: tuple[Any, ...]) -> None:
        with self._lock:
            self._backlog.add(Write(what, sql, params))
            if self._closed:
                log.error("the %s came after the mission history was closed: not written", what)
            self._flush()

    def _flush(self) -> None:
        if self._closed:
            return
        failed = self._backlog.flush(self._db)
        if failed is not None:
            log.error(
                "mission history write failed, kept in memory for a retry (%d waiting): %s",
                len(self._backlog),
                _explain(self.path, failed),
            )

    @property
    def unsaved(self) -> int:
        """Records waiting to be written because the database refused them for now."""
        with self._lock:
            return len(self._backlog)

    @property
    def rejected(self) -> Path:
        """The side file of records the database refused for good (see backlog.py)."""
        return self._backlog.rejected

    def rejected_count(self) -> int:
        """How many records the side file holds. Raises MemoryStoreError when it cannot say."""
        return self._backlog.rejected_count()

    # -- reading ----------------------------------------------------------------------------

    def recent(
        self,
        limit: int = 20,
        offset: int = 0,
        *,
        queued: bool = True,
        robot: RobotId | None = None,
    ) -> list[dict[str, Any]]:
        """Newest first: id, mission, status, success, response, started_at, finished_at,
        robot_id (None: run before robots were recorded).

        `queued=False` leaves out missions still waiting for their turn (`started_at` is then
        when they were accepted); `robot` keeps only that robot's missions."""
        where = ["1"] if queued else ["status != 'queued'"]
        if robot is not None:
            where.append("robot_id = ?")
        rows = self._query(
            "SELECT id, mission, status, success, response, started_at, finished_at, robot_id "
            f"FROM missions WHERE {' AND '.join(where)} ORDER BY started_at DESC LIMIT ? OFFSET ?",
            (*(() if robot is None else (robot.name,)), limit, offset),
        )
        return [dict(zip(_LISTED, row, strict=True)) for row in rows]

    def get(self, mission_id: str) -> dict[str, Any] | None:
        """The full record of one mission (plan, steps, timing, usage, refusals, the robot's
        state after) and the robot that ran it (`robot_id`)."""
        rows = self._query(
            f"SELECT {', '.join(_LISTED)}, record FROM missions WHERE id = ?", (mission_id,)
        )
        if not rows:
            return None
        mission_id, mission, status, success, response, started, finished, robot, record = rows[0]
        # A mission that never finished (queued, running, not run, interrupted) has no record:
        # what the row says is all there is.
        full = (
            json.loads(record)
            if record
            else {
                "mission_id": mission_id,
                "mission": mission,
                "response": response,
                "success": None if success is None else bool(success),
            }
        )
        full.update(status=status, started_at=started, finished_at=finished, robot_id=robot)
        return full

    def count(self) -> int:
        return int(self._query("SELECT COUNT(*) FROM missions", ())[0][0])

    def _query(self, sql: str, params: tuple[Any, ...]) -> list[tuple[Any, ...]]:
        with self._lock:
            try:
                return self._db.execute(sql, params).fetchall()
            except sqlite3.DatabaseError as exc:
                raise self._failed(exc) from exc

    def _failed(self, exc: sqlite3.DatabaseError) -> MemoryStoreError:
        return MemoryStoreError(_explain(self.path, exc))


def _explain(path: Path, exc: sqlite3.DatabaseError) -> str:
    text = str(exc)
    if "locked" in text or "busy" in text:
        return (
            f"the history database {str(path)!r} is locked by another process ({text}); "
            "wait for it, or give this process its own memory.data_dir"
        )
    if "not a database" in text or "malformed" in text or "corrupt" in text:
        return (
            f"the history database {str(path)!r} is corrupt ({text}); move it aside to "
            "keep it for inspection, and a new one will be created"
        )
    return f"the history database {str(path)!r} failed: {text}"
