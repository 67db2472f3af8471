"""The straight-leg check: would walking straight from A to B hit something, and where?"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .grid import OCCUPIED_THRESHOLD, Cell
from .objects import Belief


@dataclass(frozen=True)
class LegCheck:
    """The verdict on one straight leg. When blocked, `distance` is how far the robot's centre
    gets (metres from the start) before the body would touch `obstacle`."""

    clear: bool
    length: float
    distance: float = 0.0
    obstacle: str = ""  # "the red ball", "the wall", "an obstacle", "unmapped space"

    def message(self) -> str:
        if self.clear:
            return f"the {self.length:.1f} m leg is clear"
        if self.obstacle == "unmapped space":
            return f"the leg leaves the mapped free space at {self.distance:.1f} m"
        return f"{self.obstacle} is in the way at {self.distance:.1f} m"


def check_leg(belief: Belief, start: tuple[float, float], end: tuple[float, float]) -> LegCheck:
    """Walk the leg in half-cell steps on the inflated grid; name the first obstacle met.

    The start's own clearance zone is ignored until the body has left it (a robot that stands
    next to a wall may walk away from it), but a step that brings the body closer to an
    occupied cell while still inside the zone counts as blocked.
    """
    inflated = belief.inflated
    grid = belief.grid
    length = math.dist(start, end)
    step = grid.resolution / 2
    n = max(1, math.ceil(length / step))
    dx, dy = (end[0] - start[0]) / n, (end[1] - start[1]) / n
    leaving = inflated.is_blocked(grid.cell_of(*start))
    last_clearance = _clearance(belief, start) if leaving else 0.0
    for i in range(1, n + 1):
        x, y = start[0] + dx * i, start[1] + dy * i
        cell = grid.cell_of(x, y)
        if not inflated.is_blocked(cell):
            leaving = False
            continue
        if leaving:
            clearance = _clearance(belief, (x, y))
            if clearance >= last_clearance - 1e-9:
                last_clearance = clearance
                continue
        at = math.hypot(dx * (i - 1), dy * (i - 1))
        return LegCheck(False, length, at, blocker_near(belief, x, y))
    return LegCheck(True, length)


def _nearest_occupied(belief: Belief, x: float, y: float) -> tuple[float, Cell | None]:
    grid = belief.grid
    reach = math.ceil((belief.robot_radius + 2 * grid.resolution) / grid.resolution)
    centre = grid.cell_of(x, y)
    best, found = math.inf, None
    for r in range(centre.row - reach, centre.row + reach + 1):
        for c in range(centre.col - reach, centre.col + reach + 1):
            cell = Cell(c, r)
            v = grid.value(cell)
            if v >= OCCUPIED_THRESHOLD or (v < 0 and not belief.inflated.unknown_is_free):
                d = math.dist(grid.center_of(cell), (x, y))
                if d < best:
                    best, found = d, cell
    return best, found


def _clearance(belief: Belief, p: tuple[float, float]) -> float:
    return _nearest_occupied(belief, *p)[0]


def blocker_near(belief: Belief, x: float, y: float) -> str:
    """What keeps the body from (x, y): "the red ball", "the wall", "unmapped space"..."""
    grid = belief.grid
    if not grid.contains(grid.cell_of(x, y)):
        return "unmapped space"
    _, cell = _nearest_occupied(belief, x, y)
    if cell is None:
        return "an obstacle"
    if grid.value(cell) < 0:
        return "unmapped space"
    return belief.name_at(*grid.center_of(cell))
