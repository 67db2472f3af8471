"""Claiming: a person vouches that this robot made a place or sighting of no known robot.

Rows from before robots were recorded belong to no robot (`robot_id` NULL) and are never goals.
`claim` makes the one called `name` this robot's own, in one transaction; it refuses when there
is nothing of no known robot by that name, or when the robot already has its own (forget that
first: one robot, one place of a name).
"""

from __future__ import annotations

import sqlite3

from ..errors import ClaimError
from ..robot_config import RobotId
from .records import CLAIM_HINT

_TABLES = {"place": "places", "sighting": "sightings"}


def claim(db: sqlite3.Connection, robot: RobotId, name: str) -> list[str]:
    """Claim `name` in every table that holds it of no known robot; returns which kinds were
    claimed. Raises ClaimError (nothing changed) or sqlite3.DatabaseError."""
    db.execute("BEGIN IMMEDIATE")
    try:
        claimed = [kind for kind, table in _TABLES.items() if _claim(db, table, robot, name)]
        if not claimed:
            raise ClaimError(_nothing(db, name))
        db.execute("COMMIT")
    except BaseException:
        db.execute("ROLLBACK")
        raise
    return claimed


def _claim(db: sqlite3.Connection, table: str, robot: RobotId, name: str) -> bool:
    row = db.execute(  # the newest, should an older version have written the name twice
        f"SELECT rowid FROM {table} WHERE robot_id IS NULL AND name = ? ORDER BY rowid DESC",
        (name,),
    ).fetchone()
    if row is None:
        return False
    if db.execute(
        f"SELECT 1 FROM {table} WHERE robot_id = ? AND name = ?", (robot.name, name)
    ).fetchone():
        raise ClaimError(
            f"robot {robot.name!r} has a place called {name!r} of its own; forget it first "
            "to claim the one of no known robot"
            if table == "places"
            else f"robot {robot.name!r} has seen the {name} itself; its own sighting stands"
        )
    db.execute(f"UPDATE {table} SET robot_id = ? WHERE rowid = ?", (robot.name, row[0]))
    return True


def _nothing(db: sqlite3.Connection, name: str) -> str:
    unknown = sorted(
        {
            n
            for table in _TABLES.values()
            for (n,) in db.execute(f"SELECT name FROM {table} WHERE robot_id IS NULL")
        }
    )
    return (
        f"nothing called {name!r} belongs to no known robot; what does (from before robots "
        f"were recorded, claimable with {CLAIM_HINT} NAME): {', '.join(unknown) or 'nothing'}"
    )
