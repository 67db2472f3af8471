"""PlaceBook: named places taught at run time ("remember this spot as the kitchen").

Places from the profile are fixed; taught places live here, in the history database when
memory is enabled (so they survive restarts), else for the life of the process.
`known_places` is the one merge of the two that every reader uses (the agent's plans, the
places.list skill, the CLI, the MCP server and the web map); `Places` holds the two together
for an agent's missions.

A place's position is finite numbers, wherever it comes from (odometry can lie): `remember`
refuses any other with a PlaceError, and a row read back from the database that is not is
skipped, with a warning.

A book is one robot's (`RobotId`): it holds, and so offers as goals, only the places that robot
was taught; another robot's, in the same database, are never read into it.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

from ..errors import PlaceError
from ..robot_config import RobotId
from ..state import not_finite
from .history import MissionHistory

log = logging.getLogger(__name__)


def normalize_place(name: str) -> str:
    key = " ".join(name.strip().lower().split())
    return key[4:] if key.startswith("the ") else key


class PlaceBook:
    """`robot`'s taught places, name -> (x, y, yaw) in its world frame (SLAM's map when the
    robot has one, else odometry's): where it stood when taught."""

    def __init__(self, store: MissionHistory | None = None, *, robot: RobotId) -> None:
        self._store = store
        self.robot = robot
        self._lock = threading.Lock()
        self._places: dict[str, tuple[float, float, float]] = {}
        for name, (x, y, yaw) in store.load_places(robot).items() if store is not None else ():
            bad = not_finite(x=x, y=y, yaw=yaw)
            if bad:
                log.warning(
                    "skipped the taught place %r read from the history: its position is not "
                    "finite (%s); teach it again",
                    name,
                    bad,
                )
                continue
            self._places[name] = (x, y, yaw)

    @property
    def persistent(self) -> bool:
        return self._store is not None

    def remember(self, name: str, x: float, y: float, yaw: float) -> str:
        """Keep (x, y, yaw) (odom frame) under `name`; returns the key it is kept as. Raises
        PlaceError for a blank name or a position that is not finite numbers."""
        key = normalize_place(name)
        if not key:
            raise PlaceError("a place needs a name")
        bad = not_finite(x=x, y=y, yaw=yaw)
        if bad:
            raise PlaceError(
                f"cannot remember the {key} at a position that is not finite ({bad}); "
                "a place needs finite x, y (metres) and yaw (radians)"
            )
        with self._lock:
            self._places[key] = (x, y, yaw)
        if self._store is not None:
            self._store.save_place(self.robot, key, x, y, yaw)
        return key

    def forget(self, name: str) -> bool:
        key = normalize_place(name)
        with self._lock:
            known = self._places.pop(key, None) is not None
        if known and self._store is not None:
            self._store.delete_place(self.robot, key)
        return known

    def all(self) -> Mapping[str, tuple[float, float, float]]:
        with self._lock:
            return dict(self._places)


@dataclass(frozen=True)
class KnownPlace:
    """A named place in the odom frame: from the profile, or taught (with the heading then)."""

    x: float
    y: float
    source: Literal["profile", "taught"]
    yaw: float | None = None  # radians; taught places only

    @property
    def position(self) -> tuple[float, float]:
        return (self.x, self.y)


def known_places(
    profile: Mapping[str, tuple[float, float]], book: PlaceBook
) -> dict[str, KnownPlace]:
    """Every place the robot knows: the profile's, then taught ones. A taught place with a
    profile place's name wins (it is listed with the taught ones)."""
    taught = book.all()
    known = {
        name: KnownPlace(x, y, "profile") for name, (x, y) in profile.items() if name not in taught
    }
    known.update({name: KnownPlace(x, y, "taught", yaw) for name, (x, y, yaw) in taught.items()})
    return known


class Places:
    """The places one agent knows: its profile's (fixed) and the taught ones (a PlaceBook),
    merged by `known_places` on every read, so a place taught a moment ago is known."""

    def __init__(self, profile: Mapping[str, tuple[float, float]], book: PlaceBook) -> None:
        self.profile = profile
        self.book = book

    def known(self) -> dict[str, KnownPlace]:
        """Every place, the profile's then taught ones (a taught place wins its name)."""
        return known_places(self.profile, self.book)

    def positions(self) -> dict[str, tuple[float, float]]:
        """name -> (x, y) of every known place: what plans and their checks read."""
        return {name: place.position for name, place in self.known().items()}
