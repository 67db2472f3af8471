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
from .backlog import Backlog, Write
from .lease import Lease, live_owners

log = logging.getLogger(__name__)

_SCHEMA = """
CREATE TABLE IF NOT EXISTS missions (
    id TEXT PRIMARY KEY,
    mission TEXT NOT NULL,
    status TEXT NOT NULL,
    success INTEGER,
    response TEXT,
    started_at REAL NOT NULL,
    finished_at REAL,
    record TEXT,
    owner TEXT
);
CREATE INDEX IF NOT EXISTS missions_started ON missions (started_at);
CREATE TABLE IF NOT EXISTS places (
    name TEXT PRIMARY KEY,
    x REAL NOT NULL,
    y REAL NOT NULL,
    yaw REAL NOT NULL,
    created_at REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS sightings (
    name TEXT PRIMARY KEY,
    x REAL NOT NULL,
    y REAL NOT NULL,
    radius REAL NOT NULL,
    confidence REAL NOT NULL,
    stamp REAL NOT NULL,
    seen_at REAL NOT NULL
);
"""


INTERRUPTED = "interrupted: the process running it ended before it finished"
NEVER_STARTED = "not run: the process that accepted it ended before its turn"


class MissionHistory:
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
            self._db.executescript(_SCHEMA)
            columns = [row[1] for row in self._db.execute("PRAGMA table_info(missions)")]
            if "owner" not in columns:  # a file from before owners were recorded
                self._db.execute("ALTER TABLE missions ADD COLUMN owner TEXT")
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

    def mission_queued(self, mission_id: str, mission: str, queued_at: float) -> None:
        """An interface accepted the mission; it waits for its turn."""
        self._write(
            f"queued mission {mission_id}",
            "INSERT OR REPLACE INTO missions (id, mission, status, started_at, owner) "
            "VALUES (?, ?, 'queued', ?, ?)",
            (mission_id, mission, queued_at, self._owner()),
        )

    def mission_started(self, mission_id: str, mission: str, started_at: float) -> None:
        self._write(
            f"started mission {mission_id}",
            "INSERT OR REPLACE INTO missions (id, mission, status, started_at, owner) "
            "VALUES (?, ?, 'running', ?, ?)",
            (mission_id, mission, started_at, self._owner()),
        )

    def mission_not_run(
        self, mission_id: str, mission: str, reason: str, finished_at: float
    ) -> None:
        """A mission that was accepted but never started (dropped, cancelled, refused)."""
        self._write(
            f"mission {mission_id} not run",
            "INSERT INTO missions (id, mission, status, success, response, started_at, "
            "finished_at) VALUES (?, ?, 'not_run', 0, ?, ?, ?) ON CONFLICT(id) DO UPDATE SET "
            "status = 'not_run', success = 0, response = excluded.response, "
            "finished_at = excluded.finished_at",
            (mission_id, mission, reason, finished_at, finished_at),
        )

    def mission_finished(self, record: dict[str, Any], finished_at: float) -> None:
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
            )
        except (KeyError, TypeError, ValueError) as exc:  # not a result's record
            with self._lock:
                self._backlog.set_aside(Write(f"finished mission {mission_id}", "", (record,)), exc)
            return
        self._write(
            f"finished mission {mission_id}",
            "INSERT INTO missions (id, mission, status, success, response, started_at, "
            "finished_at, record) VALUES (?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT(id) DO UPDATE SET "
            "status = excluded.status, success = excluded.success, "
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
        self, limit: int = 20, offset: int = 0, *, queued: bool = True
    ) -> list[dict[str, Any]]:
        """Newest first: id, mission, status, success, response, started_at, finished_at.

        `queued=False` leaves out missions still waiting for their turn (`started_at` is then
        when they were accepted)."""
        where = "" if queued else "WHERE status != 'queued' "
        rows = self._query(
            "SELECT id, mission, status, success, response, started_at, "
            f"finished_at FROM missions {where}ORDER BY started_at DESC "
            "LIMIT ? OFFSET ?",
            (limit, offset),
        )
        keys = ("id", "mission", "status", "success", "response", "started_at", "finished_at")
        return [dict(zip(keys, row, strict=True)) for row in rows]

    def get(self, mission_id: str) -> dict[str, Any] | None:
        """The full record of one mission (plan, steps, timing, usage, refusals, robot)."""
        rows = self._query(
            "SELECT id, mission, status, success, response, started_at, "
            "finished_at, record FROM missions WHERE id = ?",
            (mission_id,),
        )
        if not rows:
            return None
        mission_id, mission, status, success, response, started, finished, record = rows[0]
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
        full.update(status=status, started_at=started, finished_at=finished)
        return full

    def count(self) -> int:
        return int(self._query("SELECT COUNT(*) FROM missions", ())[0][0])

    def _query(self, sql: str, params: tuple[Any, ...]) -> list[tuple[Any, ...]]:
        with self._lock:
            try:
                return self._db.execute(sql, params).fetchall()
            except sqlite3.DatabaseError as exc:
                raise MemoryStoreError(_explain(self.path, exc)) from exc

    # -- places (same file) -----------------------------------------------------------------

    def save_place(self, name: str, x: float, y: float, yaw: float) -> None:
        self._write(
            f"place {name!r}",
            "INSERT OR REPLACE INTO places (name, x, y, yaw, created_at) VALUES (?, ?, ?, ?, ?)",
            (name, x, y, yaw, time.time()),
        )

    def delete_place(self, name: str) -> None:
        self._write(f"forgetting the place {name!r}", "DELETE FROM places WHERE name = ?", (name,))

    def load_places(self) -> dict[str, tuple[float, float, float]]:
        rows = self._query("SELECT name, x, y, yaw FROM places ORDER BY name", ())
        return {name: (x, y, yaw) for name, x, y, yaw in rows}

    # -- sightings (same file): the latest of each object seen --------------------------------

    def save_sighting(
        self, name: str, x: float, y: float, radius: float, confidence: float, stamp: float
    ) -> None:
        self._write(
            f"sighting of {name!r}",
            "INSERT OR REPLACE INTO sightings (name, x, y, radius, confidence, stamp, "
            "seen_at) VALUES (?, ?, ?, ?, ?, ?, ?)",
            (name, x, y, radius, confidence, stamp, time.time()),
        )

    def load_sightings(self) -> list[tuple[str, float, float, float, float, float, float]]:
        """(name, x, y, radius, confidence, robot stamp, wall-clock seen_at), by name."""
        return [
            tuple(r)
            for r in self._query(
                "SELECT name, x, y, radius, confidence, stamp, seen_at FROM sightings "
                "ORDER BY name",
                (),
            )
        ]


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
