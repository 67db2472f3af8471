"""Known objects and the belief that holds them with the map."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

from .grid import OccupancyGrid
from .inflation import DEFAULT_ROBOT_RADIUS, InflatedGrid, inflate


@dataclass(frozen=True)
class KnownObject:
    """Something the robot knows stands at (x, y) in the map frame, as a circle of `radius`."""

    name: str
    x: float
    y: float
    radius: float = 0.25
    confidence: float = 1.0  # 0..1: how sure the source (simulator, detector) was
    stamp: float = 0.0  # robot-clock seconds when it was last seen

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise ValueError("an object needs a non-empty name")
        if not (math.isfinite(self.x) and math.isfinite(self.y)):
            raise ValueError(f"object {self.name!r}: position must be finite")
        if not (math.isfinite(self.radius) and self.radius >= 0):
            raise ValueError(f"object {self.name!r}: radius must be >= 0, got {self.radius}")

    @property
    def the_name(self) -> str:
        """How a sentence refers to it: "the red ball"."""
        return self.name if self.name.lower().startswith("the ") else f"the {self.name}"


@dataclass
class Belief:
    """The map and the objects on it. `room` (x_min, x_max, y_min, y_max), when known, lets
    checks call the cells along its edges "the wall"."""

    grid: OccupancyGrid
    objects: tuple[KnownObject, ...] = ()
    robot_radius: float = DEFAULT_ROBOT_RADIUS
    room: tuple[float, float, float, float] | None = None
    _inflated: InflatedGrid | None = field(default=None, repr=False, compare=False)

    @property
    def inflated(self) -> InflatedGrid:
        """The inflated grid for the robot's radius (cached; call `changed` after edits)."""
        if self._inflated is None:
            self._inflated = inflate(self.grid, self.robot_radius)
        return self._inflated

    def changed(self) -> None:
        self._inflated = None

    def find(self, name: str) -> KnownObject | None:
        key = object_key(name)
        return next((o for o in self.objects if object_key(o.name) == key), None)

    def name_at(self, x: float, y: float) -> str:
        """What the obstacle at (x, y) is, as a sentence says it."""
        tolerance = 2 * self.grid.resolution
        near = [o for o in self.objects if math.hypot(o.x - x, o.y - y) <= o.radius + tolerance]
        if near:
            best = min(near, key=lambda o: math.hypot(o.x - x, o.y - y) - o.radius)
            return best.the_name
        if self.room is not None:
            x_min, x_max, y_min, y_max = self.room
            if min(x - x_min, x_max - x, y - y_min, y_max - y) <= tolerance:
                return "the wall"
        return "an obstacle"


def object_key(name: str) -> str:
    """How names compare: case, spacing and a leading "the" do not matter."""
    key = " ".join(name.strip().lower().split())
    return key[4:] if key.startswith("the ") else key


def merge_sightings(known: Iterable[KnownObject], seen: Iterable[KnownObject]
                    ) -> tuple[KnownObject, ...]:
    """`known` updated with new sightings (from any source: simulator, detector): a sighting
    replaces the known object of the same name unless that one was seen later; new names are
    appended in the order seen. One object per name: the latest sighting is where it is."""
    merged = {object_key(o.name): o for o in known}
    for o in seen:
        key = object_key(o.name)
        if key not in merged or merged[key].stamp <= o.stamp:
            merged[key] = o
    return tuple(merged.values())
