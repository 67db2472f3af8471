"""Where to look next for something not seen yet: coverage of the map and the next viewpoint.

The map is cut into coarse spots (`spot` metres). A look-around from a point sees every spot
within `view_range` whose centre a straight ray reaches without crossing an occupied cell
(an occupied spot counts once the ray reaches its edge: an object is seen from outside).
The next viewpoint is the free, reachable point inside the allowed area that sees the most
unseen spots per metre walked. Pure Python; the walking and looking is the skill's business.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from ..errors import PlanError
from .grid import OCCUPIED_THRESHOLD, Cell, OccupancyGrid
from .objects import Belief
from .planner import Path, plan_path

Point = tuple[float, float]
_SEE_INTO = 0.5  # metres a ray may stop short of a spot's centre and still see the spot
_CANDIDATES_PLANNED = 8  # best-scored viewpoints that get a real path before one is chosen


@dataclass(frozen=True)
class Viewpoint:
    """Where to look from next, the path there, and how many unseen spots it should show."""

    point: Point
    path: Path
    gain: int


class Coverage:
    """Which spots of the belief's map the robot has looked at."""

    def __init__(self, belief: Belief, view_range: float = 4.0, spot: float = 0.5) -> None:
        if not (view_range > 0 and spot > 0):
            raise ValueError("view_range and spot must be > 0 metres")
        self.belief = belief
        self.view_range = view_range
        self.spot = spot
        grid = belief.grid
        xs = [grid.center_of(c)[0] for c in _corners(grid)]
        ys = [grid.center_of(c)[1] for c in _corners(grid)]
        self._x0, self._y0 = min(xs), min(ys)
        cols = max(1, math.ceil((max(xs) - self._x0) / spot))
        rows = max(1, math.ceil((max(ys) - self._y0) / spot))
        self.spots: list[Point] = [
            (self._x0 + (i + 0.5) * spot, self._y0 + (j + 0.5) * spot)
            for j in range(rows)
            for i in range(cols)
            if grid.contains(grid.cell_of(self._x0 + (i + 0.5) * spot, self._y0 + (j + 0.5) * spot))
        ]
        self.seen: set[Point] = set()
        self.looked_from: list[Point] = []

    @property
    def unseen(self) -> int:
        return len(self.spots) - len(self.seen)

    def visible_from(self, p: Point, among: list[Point] | None = None) -> list[Point]:
        """The spots (of `among`, default all) a look-around from `p` sees."""
        r = self.view_range
        return [
            s
            for s in (self.spots if among is None else among)
            if math.dist(p, s) <= r and self._ray_reaches(p, s)
        ]

    def look(self, p: Point) -> int:
        """Record a look-around from `p`; returns how many spots were new."""
        self.looked_from.append(p)
        new = [s for s in self.visible_from(p, self._unseen_list()) if s not in self.seen]
        self.seen.update(new)
        return len(new)

    def next_viewpoint(
        self, start: Point, allowed: Callable[[Point], bool], max_path: float
    ) -> Viewpoint | None:
        """The best next place to look from: free on the inflated map, `allowed` (inside the
        geofence), reachable by a path of at most `max_path` metres, seeing unseen spots. None
        when no such place is left."""
        unseen = self._unseen_list()
        if not unseen or max_path <= 0:
            return None
        inflated = self.belief.inflated
        r = self.view_range
        scored: list[tuple[float, Point, int]] = []
        for c in self.spots:
            straight = math.dist(start, c)
            if straight > max_path or straight < self.spot or not inflated.is_free_at(*c):
                continue
            if not allowed(c):
                continue
            near = sum(1 for s in unseen if math.dist(c, s) <= r)  # an upper bound on the gain
            if near:
                scored.append((near / (straight + 2.0), c, near))
        scored.sort(reverse=True)
        best: Viewpoint | None = None
        best_score = 0.0
        for bound, c, _ in scored[: _CANDIDATES_PLANNED * 4]:
            if bound <= best_score:
                break  # no later candidate can beat the best found (scores only shrink)
            gain = len(self.visible_from(c, unseen))
            if gain == 0 or gain / (math.dist(start, c) + 2.0) <= best_score:
                continue
            try:
                path = plan_path(inflated, start, c)
            except PlanError:
                continue
            if path.length > max_path:
                continue
            score = gain / (path.length + 2.0)
            if score > best_score:
                best, best_score = Viewpoint(c, path, gain), score
        return best

    def _unseen_list(self) -> list[Point]:
        return [s for s in self.spots if s not in self.seen]

    def _ray_reaches(self, a: Point, b: Point) -> bool:
        grid = self.belief.grid
        length = math.dist(a, b)
        reach = max(0.0, length - _SEE_INTO)
        step = grid.resolution
        n = math.ceil(reach / step)
        if n == 0:
            return True
        dx, dy = (b[0] - a[0]) / length * step, (b[1] - a[1]) / length * step
        for i in range(1, n + 1):
            cell = grid.cell_of(a[0] + dx * i, a[1] + dy * i)
            if grid.contains(cell) and grid.value(cell) >= OCCUPIED_THRESHOLD:
                return False
        return True


def _corners(grid: OccupancyGrid) -> list[Cell]:
    w, h = grid.width - 1, grid.height - 1
    return [Cell(0, 0), Cell(w, 0), Cell(0, h), Cell(w, h)]
