"""The history's write backlog: records waiting for the database, and those it refused for good.

Records are written in order. A write that fails for now (the file locked past the busy
time-out, the disk full) stays at the head of the backlog and is retried with the next write.
A record the database refuses for good (a constraint it breaks, such as NOT NULL for a NaN,
which SQLite stores as NULL; a value SQLite cannot bind or hold) would block every record
after it forever: it is set aside instead, as one line of strict JSON with its error in the
side file beside the database (`history.rejected.jsonl`), and the records after it land.
Not thread-safe: the history holds its lock around every call.
"""

from __future__ import annotations

import logging
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import jsonout
from ..errors import MemoryStoreError

log = logging.getLogger(__name__)

# Errors of the record itself, which retrying cannot fix; anything else (locked, disk full,
# I/O) may pass later. ValueError covers text SQLite cannot encode (a lone surrogate),
# OverflowError an integer beyond 64 bits, ProgrammingError a value of a type it cannot bind.
REFUSED_FOR_GOOD = (
    sqlite3.IntegrityError,
    sqlite3.InterfaceError,
    sqlite3.DataError,
    sqlite3.ProgrammingError,
    OverflowError,
    TypeError,
    ValueError,
)


@dataclass(frozen=True)
class Write:
    """One record for the database: what it is (for people), its statement and values."""

    what: str
    sql: str
    params: tuple[Any, ...]


class Backlog:
    """Records not yet written, in order, and the side file `rejected` for those refused."""

    def __init__(self, rejected: Path) -> None:
        self.rejected = rejected
        self._waiting: list[Write] = []

    def __len__(self) -> int:
        return len(self._waiting)

    def add(self, write: Write) -> None:
        self._waiting.append(write)

    def flush(self, db: sqlite3.Connection) -> sqlite3.DatabaseError | None:
        """Write what waits, in order. Returns the error that stopped it for now (the rest
        waits for the next flush), or None when everything was written or set aside."""
        while self._waiting:
            write = self._waiting[0]
            try:
                db.execute(write.sql, write.params)
            except REFUSED_FOR_GOOD as exc:
                self.set_aside(write, exc)
            except sqlite3.DatabaseError as exc:
                return exc
            self._waiting.pop(0)
        return None

    def set_aside(self, write: Write, exc: Exception) -> None:
        """Append a record refused for good to the side file, one line of strict JSON: when,
        the error, what it is, and its statement and values (a value that is not finite is
        null there; the error says what the database made of it)."""
        line = {
            "rejected_at": time.time(),
            "error": f"{type(exc).__name__}: {exc}",
            "what": write.what,
            "sql": write.sql,
            "params": list(write.params),
        }
        try:
            text = jsonout.dumps(line, default=repr)
        except ValueError:  # a value that holds itself: its text is what can be kept
            text = jsonout.dumps({**line, "params": repr(write.params)})
        try:
            with self.rejected.open("a", encoding="utf-8") as side:
                side.write(text + "\n")
        except OSError as err:
            log.error(
                "the mission history refused the %s for good (%s), and it cannot be set "
                "aside in %s (%s); the record was: %s",
                write.what,
                exc,
                self.rejected,
                err,
                text,
            )
            return
        log.error(
            "the mission history refused the %s for good (%s); it is set aside in %s and "
            "the records after it are written",
            write.what,
            exc,
            self.rejected,
        )

    def rejected_count(self) -> int:
        """How many records the side file holds. Raises MemoryStoreError when it cannot say."""
        try:
            with self.rejected.open(encoding="utf-8") as side:
                return sum(1 for line in side if line.strip())
        except FileNotFoundError:
            return 0
        except OSError as exc:
            raise MemoryStoreError(f"cannot read {str(self.rejected)!r}: {exc}") from exc
