"""The history database's tables, and bringing a file an older version wrote up to them in place.

Every place, sighting and mission carries `robot_id`: the robot that made it (`RobotId`).
A file from before robots were recorded (schema 0) is migrated when it is opened, in one
transaction that keeps every row: missions gain the column, places and sightings are rebuilt
so that two robots may each know a "kitchen". The rows it had keep `robot_id` NULL: of no known
robot, history only, never a goal until a person claims them (`shadowhound places --claim`).
Processes that open the file together migrate it once (the first holds the write lock; the
others find it done).
"""

from __future__ import annotations

import logging
import sqlite3

log = logging.getLogger(__name__)

VERSION = 1  # PRAGMA user_version of a file with robot_id everywhere

_MISSIONS = """
CREATE TABLE IF NOT EXISTS missions (
    id TEXT PRIMARY KEY,
    mission TEXT NOT NULL,
    status TEXT NOT NULL,
    success INTEGER,
    response TEXT,
    started_at REAL NOT NULL,
    finished_at REAL,
    record TEXT,
    owner TEXT,
    robot_id TEXT
)"""
# robot_id NULL: made before robots were recorded. NULLs never equal each other in UNIQUE, nor
# any robot in `robot_id = ?`: such a row can never be read as a robot's own.
_PLACES = """
CREATE TABLE IF NOT EXISTS {name} (
    robot_id TEXT,
    name TEXT NOT NULL,
    x REAL NOT NULL,
    y REAL NOT NULL,
    yaw REAL NOT NULL,
    created_at REAL NOT NULL,
    UNIQUE (robot_id, name)
)"""
_SIGHTINGS = """
CREATE TABLE IF NOT EXISTS {name} (
    robot_id TEXT,
    name TEXT NOT NULL,
    x REAL NOT NULL,
    y REAL NOT NULL,
    radius REAL NOT NULL,
    confidence REAL NOT NULL,
    stamp REAL NOT NULL,
    seen_at REAL NOT NULL,
    UNIQUE (robot_id, name)
)"""
_INDEXES = (
    "CREATE INDEX IF NOT EXISTS missions_started ON missions (started_at)",
    "CREATE INDEX IF NOT EXISTS missions_robot ON missions (robot_id, started_at)",
)
_COPIED = {
    "places": "name, x, y, yaw, created_at",
    "sightings": "name, x, y, radius, confidence, stamp, seen_at",
}


def prepare(db: sqlite3.Connection) -> None:
    """Create the tables of a new file, or migrate an older one in place. Raises
    sqlite3.DatabaseError (the caller names the file)."""
    if db.execute("PRAGMA user_version").fetchone()[0] >= VERSION:
        return  # up to date (or newer: a later version's columns are its own to keep)
    db.execute("BEGIN IMMEDIATE")  # one process migrates; the others wait, then find it done
    try:
        db.execute(_MISSIONS)
        db.execute(_PLACES.format(name="places"))
        db.execute(_SIGHTINGS.format(name="sightings"))
        missions = _columns(db, "missions")
        if "owner" not in missions:  # a file from before owners were recorded
            db.execute("ALTER TABLE missions ADD COLUMN owner TEXT")
        if "robot_id" not in missions:
            db.execute("ALTER TABLE missions ADD COLUMN robot_id TEXT")
        kept = {table: _rebuild(db, table) for table in _COPIED if _needs_robot(db, table)}
        for sql in _INDEXES:
            db.execute(sql)
        db.execute(f"PRAGMA user_version = {VERSION}")
        db.execute("COMMIT")
    except BaseException:
        db.execute("ROLLBACK")
        raise
    kept = {table: n for table, n in kept.items() if n}
    if kept:
        log.warning(
            "the history database was written before robots were recorded: kept %s of no "
            "known robot; they are never goals until claimed (shadowhound places --claim NAME)",
            " and ".join(f"{n} {table}" for table, n in kept.items()),
        )


def _columns(db: sqlite3.Connection, table: str) -> list[str]:
    return [row[1] for row in db.execute(f"PRAGMA table_info({table})")]


def _needs_robot(db: sqlite3.Connection, table: str) -> bool:
    return "robot_id" not in _columns(db, table)


def _rebuild(db: sqlite3.Connection, table: str) -> int:
    """Copy `table` of schema 0 (its name the key) into one keyed by (robot_id, name), every
    row of no known robot. Returns how many rows it kept."""
    shape = _PLACES if table == "places" else _SIGHTINGS
    db.execute(shape.format(name=f"{table}_v1"))
    columns = _COPIED[table]
    db.execute(f"INSERT INTO {table}_v1 ({columns}) SELECT {columns} FROM {table}")
    db.execute(f"DROP TABLE {table}")
    db.execute(f"ALTER TABLE {table}_v1 RENAME TO {table}")
    return int(db.execute(f"SELECT COUNT(*) FROM {table}").fetchone()[0])
