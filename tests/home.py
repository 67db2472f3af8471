"""The tests' homes: every test gets an empty one, and the user's own is left alone.

Profiles keep history in `~/.shadowhound`; ROS 2 logs to `~/.ros`, Chromium and the MCP
Inspector keep state under the home too. A test that reached the real home would read what
earlier runs left there (a model's prompt grew with remembered missions) and write into the
user's data. So, before anything runs, the session points HOME (and the XDG directories and
the memory directory) at a temporary directory, which child processes inherit; each test then
gets a fresh, empty home of its own (`tests/conftest.py`). At the end, the real home is checked
unchanged (`RealHome`).
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path

# Where the suite's programs would write in a home (found by running the suite with an empty
# one): the agent's memory, ROS 2 logs, Chromium, the MCP Inspector, what Chromium and node
# keep under .cache/.config/.local/.pki.
WATCHED = (".shadowhound", ".ros", ".mcp-inspector", ".config", ".local", ".pki")
# Caches other programs on the machine (pip, a package manager) write on their own.
CACHE = ".cache"
CACHE_OTHERS = ("pip", "uv", "pypoetry")


def home_env(home: Path) -> dict[str, str]:
    """The environment that makes `home` the home of this process and its children."""
    return {
        "HOME": str(home),
        "XDG_CONFIG_HOME": str(home / ".config"),
        "XDG_CACHE_HOME": str(home / ".cache"),
        "XDG_DATA_HOME": str(home / ".local" / "share"),
        "XDG_STATE_HOME": str(home / ".local" / "state"),
        "SHADOWHOUND_MEMORY__DATA_DIR": str(home / ".shadowhound"),
    }


Snapshot = dict[str, tuple[int, int, int]]  # relative path -> (mode, size, mtime ns)


def snapshot(home: Path) -> Snapshot:
    """What the suite could change in `home`: its own entries, and everything under the
    directories its programs write to (not the rest of the home: it can be large)."""
    found: Snapshot = {}

    def add(path: Path) -> None:
        try:
            info = path.lstat()
        except FileNotFoundError:
            return
        found[str(path.relative_to(home))] = (info.st_mode, info.st_size, info.st_mtime_ns)

    def walk(top: Path, skip: tuple[str, ...] = ()) -> None:
        add(top)
        if not top.is_dir() or top.is_symlink():
            return
        for dirpath, dirnames, filenames in os.walk(top, onerror=lambda _e: None):
            if Path(dirpath) == top:
                dirnames[:] = [d for d in dirnames if d not in skip]
            for name in dirnames + filenames:
                add(Path(dirpath, name))

    try:
        entries = sorted(home.iterdir())
    except FileNotFoundError:
        return found
    for entry in entries:
        add(entry)
    for name in WATCHED:
        walk(home / name)
    walk(home / CACHE, skip=CACHE_OTHERS)
    return found


def changes(before: Snapshot, after: Snapshot) -> list[str]:
    """Readable differences between two snapshots (empty when nothing changed)."""
    out = [f"created {p}" for p in sorted(after.keys() - before.keys())]
    out += [f"removed {p}" for p in sorted(before.keys() - after.keys())]
    for path in sorted(before.keys() & after.keys()):
        if before[path] != after[path] and not (
            stat.S_ISDIR(before[path][0]) and stat.S_ISDIR(after[path][0])
        ):
            out.append(f"modified {path}")
    return out


@dataclass
class RealHome:
    """The user's home as the session found it, to compare with at the end."""

    path: Path
    before: Snapshot

    @classmethod
    def record(cls, path: Path) -> RealHome:
        return cls(path, snapshot(path))

    def changes(self) -> list[str]:
        return changes(self.before, snapshot(self.path))
