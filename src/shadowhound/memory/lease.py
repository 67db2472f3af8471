"""Leases: which process owns the running and queued missions in a shared history database.

A process that records a mission as running or queued first takes a lease: an exclusive
`flock` on a small file of its own in a folder beside the database, named by a token that the
mission rows carry. The kernel drops the lock when the process ends, however it ends (a crash,
SIGKILL, the OOM killer), so another process can tell a live owner from a dead one without
trusting pids (reused), clocks or heartbeats, also across PID namespaces (containers sharing
the data directory). Where `flock` does not exist (Windows) no owner can be seen alive.
"""

from __future__ import annotations

import contextlib
import os
import re
import socket
import uuid
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

_SUFFIX = ".lock"
_UNSAFE = re.compile(r"[^A-Za-z0-9.-]+")


class Lease:
    """This process's claim, held until `release()` or until the process ends."""

    def __init__(self, folder: Path) -> None:
        folder.mkdir(parents=True, exist_ok=True)
        host = _UNSAFE.sub("-", socket.gethostname())[:40] or "host"
        self.token = f"{host}-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        self.path = folder / (self.token + _SUFFIX)
        # Locked under a temporary name, then renamed: a lease file that others can see is
        # always already locked, so no one mistakes a lease being taken for a dead one.
        claiming = folder / (self.token + ".claim")
        self._fd = os.open(claiming, os.O_CREAT | os.O_EXCL | os.O_RDWR, 0o644)
        try:
            if fcntl is not None:
                fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            os.write(self._fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode())
            os.replace(claiming, self.path)
        except OSError:
            os.close(self._fd)
            with contextlib.suppress(OSError):
                claiming.unlink()
            raise

    def release(self) -> None:
        """Give the lease up (the process's missions count as ended from now on)."""
        if self._fd < 0:
            return
        with contextlib.suppress(OSError):
            self.path.unlink()
        os.close(self._fd)
        self._fd = -1


def live_owners(folder: Path) -> set[str]:
    """Tokens whose process still lives. Leases of ended processes are deleted on the way."""
    live: set[str] = set()
    if fcntl is None or not folder.is_dir():
        return live
    for path in folder.glob("*" + _SUFFIX):
        try:
            fd = os.open(path, os.O_RDWR)
        except OSError:  # released meanwhile
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            live.add(path.name[: -len(_SUFFIX)])
        except OSError:
            continue
        else:  # nobody holds it: its process has ended
            with contextlib.suppress(OSError):
                path.unlink()
        finally:
            os.close(fd)
    return live
