"""The tests' homes: every test gets an empty one, and the user's own is left alone.

Profiles keep history in `~/.shadowhound`; ROS 2 logs to `~/.ros`, Chromium and the MCP
Inspector keep state under the home too. A test that reached the real home would read what
earlier runs left there (a model's prompt grew with remembered missions) and write into the
user's data. So, before anything runs, the session points HOME (the XDG directories, ROS_HOME,
the memory directory) at a temporary directory, which child processes inherit; each test then
gets a fresh, empty home of its own (`tests/conftest.py`). At the end, what the project keeps
in the real home is checked unchanged (`RealHome`).
"""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path

# What the check at the end compares: what only this project's programs write in a home (the
# agent's memory; the MCP Inspector's state). Not .ros, .config, .cache: the user's own ROS
# tools and browser write there while the tests run (on this machine, other engineers' test
# runs did). The tests' homes take those writes all the same (HOME, XDG_*, ROS_HOME).
WATCHED = (".shadowhound", ".mcp-inspector")


def home_env(home: Path) -> dict[str, str]:
    """The environment that makes `home` the home of this process and its children."""
    return {
        "HOME": str(home),
        "XDG_CONFIG_HOME": str(home / ".config"),
        "XDG_CACHE_HOME": str(home / ".cache"),
        "XDG_DATA_HOME": str(home / ".local" / "share"),
        "XDG_STATE_HOME": str(home / ".local" / "state"),
        "ROS_HOME": str(home / ".ros"),  # ROS 2 logs, also where the user set ROS_HOME
        "ROS_LOG_DIR": str(home / ".ros" / "log"),
        "SHADOWHOUND_MEMORY__DATA_DIR": str(home / ".shadowhound"),
    }


Snapshot = dict[str, tuple[int, int, int]]  # relative path -> (mode, size, mtime ns)


def snapshot(home: Path) -> Snapshot:
    """Everything under the WATCHED directories of `home` (and whether they exist)."""
    found: Snapshot = {}

    def add(path: Path) -> None:
        try:
            info = path.lstat()
        except FileNotFoundError:
            return
        found[str(path.relative_to(home))] = (info.st_mode, info.st_size, info.st_mtime_ns)

    for name in WATCHED:
        top = home / name
        add(top)
        if top.is_dir() and not top.is_symlink():
            for dirpath, dirnames, filenames in os.walk(top, onerror=lambda _e: None):
                for entry in dirnames + filenames:
                    add(Path(dirpath, entry))
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
