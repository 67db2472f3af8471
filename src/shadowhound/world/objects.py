"""Known objects and the belief that holds them with the map.

Sightings enter the belief through one call, whatever saw them (the simulator's camera, a ROS
detections topic, a test): `Belief.sight(name, x, y, stamp, confidence)`, with (x, y) in the
map/odom frame. A newer sighting of the same name replaces the older one (objects are assumed
unique by name: "the red ball"). Reading is `find(name)` and `objects`.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

from .grid import OCCUPIED_THRESHOLD, OccupancyGrid
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
    # Known from an earlier run (memory): its stamp is on another run's clock, so any fresh
    # sighting replaces it.
    remembered: bool = False

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
    """The map and the objects on it. `objects` are what the robot knows stands where (its
    sightings, or what it was told); `labels` are names a labelled map gives its obstacles
    (the simulator's scene), used only to say what is in the way, never as a place to go.
    `room` (x_min, x_max, y_min, y_max), when known, lets checks call the cells along its
    edges "the wall"."""

    grid: OccupancyGrid
    objects: tuple[KnownObject, ...] = ()
    robot_radius: float = DEFAULT_ROBOT_RADIUS
    room: tuple[float, float, float, float] | None = None
    _inflated: InflatedGrid | None = field(default=None, repr=False, compare=False)
    labels: tuple[KnownObject, ...] = ()
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    @property
    def inflated(self) -> InflatedGrid:
        """The inflated grid for the robot's radius (cached; call `changed` after edits)."""
        if self._inflated is None:
            self._inflated = inflate(self.grid, self.robot_radius)
        return self._inflated

    def changed(self) -> None:
        self._inflated = None

    def replace_grid(self, grid: OccupancyGrid) -> None:
        """A new map (a map server's or SLAM's next message) for the same world: the objects
        known stay. Inflated before the swap, so a planner never sees a half-made one."""
        inflated = inflate(grid, self.robot_radius)
        with self._lock:
            self.grid, self._inflated = grid, inflated

    def sight(
        self,
        name: str,
        x: float,
        y: float,
        stamp: float,
        confidence: float = 1.0,
        radius: float | None = None,
    ) -> KnownObject:
        """Remember that `name` was seen at (x, y) (map/odom frame, metres) at `stamp` (robot
        clock seconds) with `confidence` in [0, 1]. Replaces an older sighting of the same name;
        an older stamp than the one known is ignored. `radius` None: estimated from the map
        (how far the occupied cells around the point reach), else 0.25 m. Thread-safe.
        Raises ValueError on a blank name, a non-finite position or a confidence outside 0..1."""
        if not (math.isfinite(confidence) and 0.0 <= confidence <= 1.0):
            raise ValueError(f"sighting of {name!r}: confidence must be in 0..1, got {confidence}")
        if not math.isfinite(stamp):
            raise ValueError(f"sighting of {name!r}: stamp must be finite, got {stamp}")
        label = object_key(name)
        seen = KnownObject(label, x, y, 0.0, confidence, stamp)  # validates name and position
        size = _extent_on_map(self.grid, x, y) if radius is None else radius
        seen = replace(seen, radius=size)  # validates the radius
        with self._lock:
            old = next((o for o in self.objects if o.name == label), None)
            if old is not None and not old.remembered and old.stamp > stamp:
                return old
            rest = tuple(o for o in self.objects if o.name != label)
            self.objects = (*rest, seen)
        return seen

    def remember(self, known: KnownObject) -> None:
        """Add an object known from elsewhere (memory of earlier missions) unless a sighting of
        the same name is already held."""
        with self._lock:
            if all(o.name != known.name for o in self.objects):
                self.objects = (*self.objects, replace(known, remembered=True))

    def find(self, name: str) -> KnownObject | None:
        """The known object `name` refers to: its exact name ("the red ball"), else the one
        object whose name ends with it ("fridge" for "white fridge"). None if none or several."""
        key = object_key(name)
        objects = self.objects
        exact = next((o for o in objects if object_key(o.name) == key), None)
        if exact is not None or not key:
            return exact
        tail = [o for o in objects if object_key(o.name).endswith(" " + key)]
        return tail[0] if len(tail) == 1 else None

    def name_at(self, x: float, y: float) -> str:
        """What the obstacle at (x, y) is, as a sentence says it."""
        tolerance = 2 * self.grid.resolution
        near = [
            o
            for o in (*self.objects, *self.labels)
            if math.hypot(o.x - x, o.y - y) <= o.radius + tolerance
        ]
        if near:
            best = min(near, key=lambda o: math.hypot(o.x - x, o.y - y) - o.radius)
            return best.the_name
        if self.room is not None:
            x_min, x_max, y_min, y_max = self.room
            if min(x - x_min, x_max - x, y - y_min, y_max - y) <= tolerance:
                return "the wall"
        return "an obstacle"


# COCO category names (a COCO detector's class names, which docs/go2.md gives) that the
# planner's words name otherwise: one thing by either name. Names not listed are the same in
# both ("chair", "person", "teddy bear").
COCO_NAMES = {
    "tv": "television",
    "couch": "sofa",
    "potted plant": "plant",
    "dining table": "table",
    "sports ball": "ball",
    "cell phone": "phone",
    "wine glass": "glass",
    "hair drier": "hair dryer",
}


def object_key(name: str) -> str:
    """How names compare: case, spacing and a leading "the" do not matter, and a COCO name is
    the planner's word for it ("the sports ball" is "ball", "a small potted plant" names a
    "small plant")."""
    key = " ".join(name.strip().lower().split())
    key = key[4:] if key.startswith("the ") else key
    for coco, word in COCO_NAMES.items():
        if key == coco or key.endswith(" " + coco):
            return key[: len(key) - len(coco)] + word
    return key


def merge_sightings(
    known: Iterable[KnownObject], seen: Iterable[KnownObject]
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


_DEFAULT_SIZE = 0.25  # metres: the radius assumed for a sighting the map shows nothing at
_MAX_SIZE = 1.5


def _extent_on_map(grid: OccupancyGrid, x: float, y: float) -> float:
    """How far the occupied cells around (x, y) reach (in 8 directions, up to 1.5 m): the
    radius of what stands there as the map shows it. 0.25 m when the map shows nothing."""

    def occupied(px: float, py: float) -> bool:
        cell = grid.cell_of(px, py)
        return grid.contains(cell) and grid.value(cell) >= OCCUPIED_THRESHOLD

    if not occupied(x, y):
        return _DEFAULT_SIZE
    step = grid.resolution / 2
    reach = 0.0
    for k in range(8):
        a = k * math.pi / 4
        d = 0.0
        c, s = math.cos(a), math.sin(a)
        while d < _MAX_SIZE and occupied(x + (d + step) * c, y + (d + step) * s):
            d += step
        reach = max(reach, d)
    # A cell counts as occupied when the object touches any of it: the blob reaches up to a
    # cell past the surface, so half a cell comes off the estimate.
    return min(_MAX_SIZE, max(grid.resolution / 2, reach - grid.resolution / 2))
