"""The simulator's ground truth as the robot senses it: range scans, contact, and the map.

Uses the scene's ray casts (scene.py), as the camera does, so the scan, the picture and the
sightings agree. Only the simulator imports this module: the rest of the system sees Scans and
grids.
"""

from __future__ import annotations

import math

from ...state import Pose2D, Scan
from ...world.grid import DEFAULT_RESOLUTION, OCCUPIED, OccupancyGrid
from ...world.objects import Belief, KnownObject
from .scene import World, ray_box, ray_circle

SCAN_BEAMS = 360
SCAN_RANGE_MIN = 0.1
SCAN_RANGE_MAX = 8.0
WALL_THICKNESS = 0.1  # metres of wall drawn outside the room on the scene's map


def cast_scan(
    world: World,
    pose: Pose2D,
    stamp: float = 0.0,
    beams: int = SCAN_BEAMS,
    range_min: float = SCAN_RANGE_MIN,
    range_max: float = SCAN_RANGE_MAX,
) -> Scan:
    """A full-circle 2D scan from `pose`: beam 0 points straight behind, counter-clockwise.
    Beams with no surface within `range_max` read infinity (as REP-117 asks)."""
    increment = 2 * math.pi / beams
    ranges = []
    for i in range(beams):
        a = pose.yaw - math.pi + i * increment
        dx, dy = math.cos(a), math.sin(a)
        t, _ = ray_box(pose.x, pose.y, dx, dy, world.bounds)
        for obj in world.objects:
            hit = ray_circle(pose.x, pose.y, dx, dy, obj)
            if hit is not None and hit < t:
                t = hit
        ranges.append(t if t < range_max else math.inf)
    return Scan(tuple(ranges), -math.pi, increment, range_min, range_max, pose, stamp)


def penetration(world: World, x: float, y: float, radius: float) -> tuple[float, str]:
    """How deep (metres) a body circle at (x, y) overlaps the scene, and what it overlaps most.

    0.0 and "" when it touches nothing.
    """
    x_min, x_max, y_min, y_max = world.bounds
    depth, what = 0.0, ""
    wall = max(x_min + radius - x, x - (x_max - radius), y_min + radius - y, y - (y_max - radius))
    if wall > 0:
        depth, what = wall, "the wall"
    for obj in world.objects:
        d = obj.radius + radius - math.hypot(obj.x - x, obj.y - y)
        if d > depth:
            depth, what = d, f"the {obj.name}"
    return depth, what


def scene_grid(world: World, resolution: float = DEFAULT_RESOLUTION) -> OccupancyGrid:
    """The scene as a map: the room free, its walls (WALL_THICKNESS outside it) and every
    object occupied (any cell they touch)."""
    x_min, x_max, y_min, y_max = world.bounds
    t = WALL_THICKNESS
    grid = OccupancyGrid.empty(x_min - t, x_max + t, y_min - t, y_max + t, resolution, value=0)
    grid.fill_rect(x_min - t, x_max + t, y_min - t, y_min, OCCUPIED)
    grid.fill_rect(x_min - t, x_max + t, y_max, y_max + t, OCCUPIED)
    grid.fill_rect(x_min - t, x_min, y_min - t, y_max + t, OCCUPIED)
    grid.fill_rect(x_max, x_max + t, y_min - t, y_max + t, OCCUPIED)
    for obj in world.objects:
        grid.fill_circle(obj.x, obj.y, obj.radius, OCCUPIED)
    return grid


def scene_belief(
    world: World, robot_radius: float, resolution: float = DEFAULT_RESOLUTION
) -> Belief:
    """Everything about the scene a robot could be told: its map and its named objects."""
    objects = tuple(KnownObject(o.name, o.x, o.y, o.radius) for o in world.objects)
    return Belief(scene_grid(world, resolution), objects, robot_radius, world.bounds)
