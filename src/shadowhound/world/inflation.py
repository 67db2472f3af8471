"""Inflation: the cells where the robot's centre may not go, given the body's radius.

A cell is blocked when it is occupied (or unknown, unless the caller allows unknown space), or
when any point of it lies closer than `radius` to an occupied cell's square. That margin is
what makes planning on cells sound: a path whose every point lies in unblocked cells keeps the
whole body circle at least `radius` from every occupied cell, whatever the path's angle.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache

from ..errors import GridError
from .grid import OCCUPIED_THRESHOLD, Cell, OccupancyGrid

DEFAULT_ROBOT_RADIUS = 0.35  # metres: a circle round the Go2's 0.70 m x 0.31 m body

_RUN = re.compile(rb"\x01+")


@dataclass(frozen=True)
class InflatedGrid:
    """The blocked mask of `grid` for a body of `radius` metres (1 = blocked, row-major)."""

    grid: OccupancyGrid
    radius: float
    blocked: bytes
    unknown_is_free: bool = False

    def is_blocked(self, cell: Cell) -> bool:
        """Blocked, or outside the map (the robot never plans off the map)."""
        if not self.grid.contains(cell):
            return True
        return self.blocked[cell.row * self.grid.width + cell.col] == 1

    def is_free_at(self, x: float, y: float) -> bool:
        return not self.is_blocked(self.grid.cell_of(x, y))


def inflate(
    grid: OccupancyGrid, radius: float = DEFAULT_ROBOT_RADIUS, *, unknown_is_free: bool = False
) -> InflatedGrid:
    """The cells the robot's centre must avoid (see the module docstring)."""
    if not (math.isfinite(radius) and radius >= 0):
        raise GridError(f"robot radius must be >= 0 metres, got {radius}")
    w, h = grid.width, grid.height
    table = bytearray(256)
    for v in range(OCCUPIED_THRESHOLD, 101):
        table[v] = 1
    obstacles = grid.cells.translate(table)
    if unknown_is_free:
        blocked = bytearray(obstacles)
    else:
        table[255] = 1
        blocked = grid.cells.translate(table)
    kernel = _kernel(radius / grid.resolution)
    centre = next(k for k in kernel if k[0] == 0)
    # The Minkowski sum of a horizontal run of obstacle cells and the disc kernel is, in each
    # kernel row, the run widened by that row's half-width: one slice assignment per run and
    # kernel row instead of one per cell.
    ones = b"\x01" * (w + 2 * (len(kernel) + 1))
    for row in range(h):
        base = row * w
        line = obstacles[base : base + w]
        if 1 not in line:
            continue
        above = obstacles[base - w : base] if row > 0 else b""
        below = obstacles[base + w : base + 2 * w] if row + 1 < h else b""
        for match in _RUN.finditer(line):
            a, b = match.start(), match.end()
            # Inside a vertical stack of obstacle cells (cells right above and below the whole
            # run) only the run's own row needs widening: rows beyond the stack get wider
            # stamps from the stack's end rows, which are nearer to them.
            interior = bool(above) and bool(below) and 0 not in above[a:b] and 0 not in below[a:b]
            for dr, half in (centre,) if interior else kernel:
                r = row + dr
                if 0 <= r < h:
                    c0, c1 = max(0, a - half), min(w, b + half)
                    blocked[r * w + c0 : r * w + c1] = ones[: c1 - c0]
    return InflatedGrid(grid, radius, bytes(blocked), unknown_is_free)


@lru_cache(maxsize=32)
def _kernel(radius_cells: float) -> tuple[tuple[int, int], ...]:
    """(row offset, column half-width) of the cells that lie, somewhere, within `radius_cells`
    of the centre cell's square (distance between the two squares' closest points < radius)."""
    if radius_cells <= 0:
        return ((0, 0),)
    reach = math.ceil(radius_cells) + 1
    rows = []
    for dr in range(-reach, reach + 1):
        gap_r = max(abs(dr) - 1, 0)  # whole cells between the two squares, vertically
        if gap_r >= radius_cells:
            continue
        half = 0
        for dc in range(reach + 1):
            gap_c = max(dc - 1, 0)
            if math.hypot(gap_r, gap_c) < radius_cells:  # hypot: no underflow for tiny radii
                half = dc
        rows.append((dr, half))
    return tuple(rows)
