"""The simulated Go2's world (its ground truth): a walled room with objects, and what is in view.

Objects are vertical cylinders in a rectangular walled room (odom frame: x forward, y left, yaw
counter-clockwise). `ray_circle` and `ray_box` are the ray casts everything here shares:
`visible_objects` (ground-truth sightings), the scan (`sensors.py`) and the picture
(`renderer.py`), so the sightings, the scan and the image agree. Standard library only.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ...state import Pose2D, Sighting, normalize_angle

Color = tuple[int, int, int]

CAMERA_HEIGHT = 0.3  # metres above the floor: roughly the Go2's head camera while standing
RAY_EPS = 1e-9  # below this, a distance along a ray (or a direction component) counts as zero


@dataclass(frozen=True)
class WorldObject:
    """A vertical cylinder standing on the floor, centred at (x, y) in the odom frame."""

    name: str
    x: float
    y: float
    radius: float = 0.25
    height: float = 0.5
    color: Color = (128, 128, 128)

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise ValueError("name must be a non-empty string")
        if not self.radius > 0:
            raise ValueError(f"radius must be > 0, got {self.radius}")
        if not self.height > 0:
            raise ValueError(f"height must be > 0, got {self.height}")
        _check_color(self.color, "color")

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "x": self.x,
            "y": self.y,
            "radius": self.radius,
            "height": self.height,
            "color": list(self.color),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], where: str = "object") -> WorldObject:
        """Build from a plain mapping; errors name the field as `where.field`."""
        if not isinstance(d, Mapping):
            raise ValueError(f"{where} must be a mapping, got {type(d).__name__}")
        _reject_unknown(d, {"name", "x", "y", "radius", "height", "color"}, where)
        for key in ("name", "x", "y"):
            if key not in d:
                raise ValueError(f"{where}.{key} is required")
        name = d["name"]
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"{where}.name must be a non-empty string, got {name!r}")
        radius = _number(d.get("radius", 0.25), f"{where}.radius")
        height = _number(d.get("height", 0.5), f"{where}.height")
        if radius <= 0:
            raise ValueError(f"{where}.radius must be > 0, got {radius}")
        if height <= 0:
            raise ValueError(f"{where}.height must be > 0, got {height}")
        return cls(
            name=name,
            x=_number(d["x"], f"{where}.x"),
            y=_number(d["y"], f"{where}.y"),
            radius=radius,
            height=height,
            color=_color(d.get("color", (128, 128, 128)), f"{where}.color"),
        )


@dataclass(frozen=True)
class World:
    """A rectangular room with walls at `bounds` = (x_min, x_max, y_min, y_max) and its objects."""

    objects: tuple[WorldObject, ...] = ()
    bounds: tuple[float, float, float, float] = (-6.0, 6.0, -6.0, 6.0)
    wall_height: float = 2.5
    wall_color: Color = (170, 176, 188)
    floor_color: Color = (112, 108, 100)
    ceiling_color: Color = (205, 215, 230)

    def __post_init__(self) -> None:
        x_min, x_max, y_min, y_max = self.bounds
        if not (x_min < x_max and y_min < y_max):
            raise ValueError(
                f"bounds must be (x_min, x_max, y_min, y_max) with min < max, got {self.bounds}"
            )
        if not self.wall_height > 0:
            raise ValueError(f"wall_height must be > 0, got {self.wall_height}")
        for name in ("wall_color", "floor_color", "ceiling_color"):
            _check_color(getattr(self, name), name)
        seen: set[str] = set()
        for obj in self.objects:
            # Skills look objects up by name, so two with one name would be ambiguous.
            key = obj.name.strip().lower()
            if key in seen:
                raise ValueError(f"objects: duplicate name {obj.name!r}")
            seen.add(key)

    def find(self, name: str) -> WorldObject | None:
        """The object called `name` (case-insensitive), or None."""
        key = name.strip().lower()
        return next((o for o in self.objects if o.name.strip().lower() == key), None)

    def contains(self, x: float, y: float) -> bool:
        x_min, x_max, y_min, y_max = self.bounds
        return x_min < x < x_max and y_min < y < y_max

    def to_dict(self) -> dict[str, Any]:
        return {
            "bounds": list(self.bounds),
            "wall_height": self.wall_height,
            "wall_color": list(self.wall_color),
            "floor_color": list(self.floor_color),
            "ceiling_color": list(self.ceiling_color),
            "objects": [o.to_dict() for o in self.objects],
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> World:
        """Build a world from a YAML/JSON-like mapping; every key is optional.

        The room is either `bounds: [x_min, x_max, y_min, y_max]` or `half_size: h` (a square
        room from -h to h). Raises ValueError naming the offending field.
        """
        if not isinstance(d, Mapping):
            raise ValueError(f"world must be a mapping, got {type(d).__name__}")
        known = {
            "objects",
            "bounds",
            "half_size",
            "wall_height",
            "wall_color",
            "floor_color",
            "ceiling_color",
        }
        _reject_unknown(d, known, "world")
        kwargs: dict[str, Any] = {}
        if "bounds" in d and "half_size" in d:
            raise ValueError("bounds and half_size: give one, not both")
        if "bounds" in d:
            raw = d["bounds"]
            if not isinstance(raw, (list, tuple)) or len(raw) != 4:
                raise ValueError(f"bounds must be [x_min, x_max, y_min, y_max], got {raw!r}")
            b = tuple(_number(v, f"bounds[{i}]") for i, v in enumerate(raw))
            if not (b[0] < b[1] and b[2] < b[3]):
                raise ValueError(f"bounds must have x_min < x_max and y_min < y_max, got {raw!r}")
            kwargs["bounds"] = b
        if "half_size" in d:
            h = _number(d["half_size"], "half_size")
            if h <= 0:
                raise ValueError(f"half_size must be > 0, got {h}")
            kwargs["bounds"] = (-h, h, -h, h)
        if "wall_height" in d:
            wall_height = _number(d["wall_height"], "wall_height")
            if wall_height <= 0:
                raise ValueError(f"wall_height must be > 0, got {wall_height}")
            kwargs["wall_height"] = wall_height
        for name in ("wall_color", "floor_color", "ceiling_color"):
            if name in d:
                kwargs[name] = _color(d[name], name)
        raw_objects = d.get("objects", [])
        if not isinstance(raw_objects, (list, tuple)):
            raise ValueError(f"objects must be a list, got {type(raw_objects).__name__}")
        objects = tuple(
            WorldObject.from_dict(o, f"objects[{i}]") for i, o in enumerate(raw_objects)
        )
        return cls(objects=objects, **kwargs)


def _reject_unknown(d: Mapping[str, Any], known: set[str], where: str) -> None:
    # A misspelt key ("radious") would otherwise silently fall back to a default.
    unknown = sorted(str(k) for k in d if k not in known)
    if unknown:
        raise ValueError(
            f"{where}: unknown field(s) {', '.join(unknown)}; "
            f"expected some of {', '.join(sorted(known))}"
        )


def _number(value: Any, where: str) -> float:
    # bool is an int subclass, but `radius: true` in YAML is a mistake, not 1.0.
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{where} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{where} must be finite, got {value!r}")
    return float(value)


def _check_color(value: Any, where: str) -> None:
    if (
        not isinstance(value, tuple)
        or len(value) != 3
        or not all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c <= 255 for c in value)
    ):
        raise ValueError(f"{where} must be (r, g, b) integers in 0..255, got {value!r}")


def _color(value: Any, where: str) -> Color:
    if not isinstance(value, (list, tuple)):
        raise ValueError(f"{where} must be [r, g, b] integers in 0..255, got {value!r}")
    color = tuple(value)
    _check_color(color, where)
    return color


DEFAULT_WORLD = World(
    objects=(
        WorldObject("red ball", 3.0, 0.0, radius=0.2, height=0.4, color=(220, 40, 40)),
        WorldObject("blue box", 2.5, 2.0, radius=0.35, height=0.6, color=(40, 80, 220)),
        WorldObject("green plant", 4.0, -2.5, radius=0.3, height=1.0, color=(40, 170, 60)),
        WorldObject("yellow chair", -2.0, 3.0, radius=0.4, height=0.9, color=(230, 200, 40)),
        WorldObject("person", 1.5, -4.0, radius=0.25, height=1.7, color=(140, 70, 170)),
        WorldObject("charging dock", -3.0, -1.0, radius=0.3, height=0.15, color=(0, 170, 170)),
        WorldObject("white fridge", 4.8, 3.2, radius=0.4, height=1.8, color=(235, 235, 230)),
        # Small, out of view at the start: what a 2-D detector calls a "bottle" (issue 24).
        WorldObject("water bottle", -2.5, -4.0, radius=0.06, height=0.3, color=(90, 200, 230)),
    )
)


def ray_circle(ox: float, oy: float, dx: float, dy: float, obj: WorldObject) -> float | None:
    """Distance along a unit ray to the front surface of `obj`, or None if the ray misses it."""
    lx = obj.x - ox
    ly = obj.y - oy
    tca = lx * dx + ly * dy
    d2 = lx * lx + ly * ly - tca * tca
    r2 = obj.radius * obj.radius
    if d2 > r2:
        return None
    t = tca - math.sqrt(r2 - d2)
    # A camera inside an object sees nothing of it; a surface behind the camera is not a hit.
    return t if t > RAY_EPS else None


def ray_box(
    ox: float, oy: float, dx: float, dy: float, bounds: tuple[float, float, float, float]
) -> tuple[float, bool]:
    """Distance along a unit ray to the room's walls, and whether the hit wall is an x-wall.

    From inside the room this is where the ray leaves it; from outside, where it first enters.
    Returns infinity when the ray never meets a wall.
    """
    x_min, x_max, y_min, y_max = bounds
    if abs(dx) > RAY_EPS:
        tx1, tx2 = (x_min - ox) / dx, (x_max - ox) / dx
        tx_near, tx_far = (tx1, tx2) if tx1 < tx2 else (tx2, tx1)
    elif x_min <= ox <= x_max:
        tx_near, tx_far = -math.inf, math.inf
    else:
        return math.inf, False
    if abs(dy) > RAY_EPS:
        ty1, ty2 = (y_min - oy) / dy, (y_max - oy) / dy
        ty_near, ty_far = (ty1, ty2) if ty1 < ty2 else (ty2, ty1)
    elif y_min <= oy <= y_max:
        ty_near, ty_far = -math.inf, math.inf
    else:
        return math.inf, False
    t_near = max(tx_near, ty_near)
    t_far = min(tx_far, ty_far)
    if t_near > t_far or t_far <= RAY_EPS:
        return math.inf, False
    if t_near > RAY_EPS:
        return t_near, tx_near >= ty_near
    return t_far, tx_far <= ty_far


def visible_objects(
    world: World, pose: Pose2D, fov_deg: float = 90.0, max_range: float = 10.0
) -> tuple[Sighting, ...]:
    """What the camera at `pose` can see: ground-truth sightings, nearest first.

    An object counts when its centre lies inside the horizontal field of view and within
    `max_range` (distance is camera to centre), it stands inside the room, and at least one ray
    across its width reaches it over the top of anything nearer. Bearings are + left of centre.
    """
    half_fov = math.radians(fov_deg) / 2.0
    found: list[Sighting] = []
    for obj in world.objects:
        distance = pose.distance_to(obj.x, obj.y)
        if distance <= obj.radius or distance > max_range or not world.contains(obj.x, obj.y):
            continue
        bearing = normalize_angle(math.atan2(obj.y - pose.y, obj.x - pose.x) - pose.yaw)
        if abs(bearing) > half_fov:
            continue
        if _unoccluded(world, pose, obj, bearing, distance, half_fov):
            found.append(Sighting(obj.name, distance, math.degrees(bearing)))
    found.sort(key=lambda s: s.distance)
    return tuple(found)


def _unoccluded(
    world: World,
    pose: Pose2D,
    target: WorldObject,
    bearing: float,
    distance: float,
    half_fov: float,
) -> bool:
    # Sample rays across the object's angular width (inside the field of view): it is visible
    # if any ray hits it before the walls and no nearer hit on that ray rises above it on screen.
    half_width = math.asin(min(1.0, target.radius / distance))
    target_rise = target.height - CAMERA_HEIGHT
    for k in range(-4, 5):
        offset = bearing + half_width * 0.9 * k / 4
        if abs(offset) > half_fov:
            continue
        angle = pose.yaw + offset
        dx, dy = math.cos(angle), math.sin(angle)
        t_target = ray_circle(pose.x, pose.y, dx, dy, target)
        if t_target is None:
            continue
        t_wall, _ = ray_box(pose.x, pose.y, dx, dy, world.bounds)
        if t_wall < t_target:
            continue
        for other in world.objects:
            if other is target:
                continue
            t = ray_circle(pose.x, pose.y, dx, dy, other)
            # The nearer object's top edge is at least as high on screen: the target is covered.
            if (
                t is not None
                and t < t_target
                and ((other.height - CAMERA_HEIGHT) * t_target >= target_rise * t)
            ):
                break
        else:
            return True
    return False


__all__ = [
    "CAMERA_HEIGHT",
    "DEFAULT_WORLD",
    "RAY_EPS",
    "Color",
    "World",
    "WorldObject",
    "ray_box",
    "ray_circle",
    "visible_objects",
]
