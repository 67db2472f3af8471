"""Updating the grid from a range scan: space a beam crossed is free, where it ended is occupied.

Marking each beam's cells one by one costs ~60,000 Python steps per 360-beam scan. Instead the
scan's free space (the star-shaped polygon through the beam end points, as seen from the
sensor) is filled row by row with slice assignments. Cells already occupied keep that value
unless a beam really passes through them (checked per cell: there are few), so an obstacle
that lies between two beams is not wiped out, while one that has moved away is cleared.
"""

from __future__ import annotations

import math
import re

from ..state import Scan
from .grid import FREE, OCCUPIED, OCCUPIED_THRESHOLD, OccupancyGrid

# Within a filled span: unknown and free-ish cells become free; occupied cells stay for the
# per-cell beam test below.
_CLEAR = bytes(FREE if v < OCCUPIED_THRESHOLD or v == 255 else v for v in range(256))
_OCCUPIED_RUN = re.compile(rb"[\x41-\x64]")  # values 65..100


def apply_scan(grid: OccupancyGrid, scan: Scan) -> int:
    """Mark the scan's free and occupied cells in `grid` (in place). Returns the hits marked."""
    res = grid.resolution
    ox, oy = grid.to_grid_frame(scan.pose.x, scan.pose.y)
    n = len(scan.ranges)
    reach = []
    for r in scan.ranges:
        if not math.isfinite(r) and r > 0:
            r = scan.range_max  # inf: nothing within reach on this beam
        elif not (math.isfinite(r) and r >= scan.range_min):
            r = 0.0  # an error or too close to trust: claim nothing along this beam
        reach.append(min(r, scan.range_max))
    verts = []

    def vertex(i: int, r: float) -> None:
        a = scan.beam_angle(i) - grid.origin.yaw
        verts.append((ox + r / res * math.cos(a), oy + r / res * math.sin(a)))

    # Between two beams only the nearer range counts as seen: where the ranges jump (an
    # object's edge), the outline steps in along the farther beam rather than cutting
    # diagonally across space that neither beam crossed.
    n = len(reach)
    full = _full_circle(scan)
    for i, r in enumerate(reach):
        # The next beam; after the last one, the first again on a full circle (the pair
        # across the wrap is as adjacent as any other).
        j = (i + 1) % n if i + 1 < n or full else i
        nxt = reach[j]
        vertex(i, r)
        if nxt < r - res:
            vertex(i, nxt)
        elif nxt > r + res:
            vertex(j, r)
    if not full:
        verts.append((ox, oy))  # a partial scan's free space is a fan from the sensor
    crossings: dict[int, list[float]] = {}
    for (x0, y0), (x1, y1) in zip(verts, verts[1:] + verts[:1], strict=True):
        if y0 == y1:
            continue
        if y0 > y1:
            x0, y0, x1, y1 = x1, y1, x0, y0
        first = max(0, math.ceil(y0 - 0.5))
        last = min(grid.height - 1, math.ceil(y1 - 0.5) - 1)
        slope = (x1 - x0) / (y1 - y0)
        for row in range(first, last + 1):
            crossings.setdefault(row, []).append(x0 + (row + 0.5 - y0) * slope)
    w = grid.width
    cells = grid.cells
    for row, xs in crossings.items():
        xs.sort()
        base = row * w
        for xa, xb in zip(xs[::2], xs[1::2], strict=False):
            c0, c1 = max(0, math.ceil(xa - 0.5)), min(w, math.floor(xb - 0.5) + 1)
            if c0 >= c1:
                continue
            span = cells[base + c0 : base + c1]
            cleared = span.translate(_CLEAR)
            for m in _OCCUPIED_RUN.finditer(span):
                col = c0 + m.start()
                if _beam_passes(scan, reach, grid, ox, oy, col, row):
                    cleared[m.start()] = FREE
            cells[base + c0 : base + c1] = cleared
    hits = 0
    for i, r in enumerate(scan.ranges):
        if scan.is_hit(r):
            a = scan.beam_angle(i) - grid.origin.yaw
            # A quarter cell past the surface: the cell behind it, whatever the rounding.
            reach_cells = r / res + 0.25
            col = math.floor(ox + reach_cells * math.cos(a))
            row = math.floor(oy + reach_cells * math.sin(a))
            if 0 <= col < w and 0 <= row < grid.height:
                cells[row * w + col] = OCCUPIED
                hits += 1
    return hits


def _full_circle(scan: Scan) -> bool:
    return len(scan.ranges) * scan.angle_increment >= 2 * math.pi - 1e-6


def _beam_passes(
    scan: Scan, reach: list[float], grid: OccupancyGrid, ox: float, oy: float, col: int, row: int
) -> bool:
    """Whether one of the two beams either side of this cell's bearing crosses the cell
    (passes within half a cell diagonal of its centre) and runs on clearly past it."""
    dx, dy = col + 0.5 - ox, row + 0.5 - oy
    dist = math.hypot(dx, dy)
    angle = math.atan2(dy, dx) + grid.origin.yaw - scan.pose.yaw - scan.angle_min
    k = angle / scan.angle_increment
    per_turn = 2 * math.pi / scan.angle_increment
    for i in {math.floor(k), math.ceil(k)}:
        i = round(i % per_turn) % max(1, round(per_turn))
        if i >= len(reach) or reach[i] / grid.resolution <= dist + 1.0:
            continue
        a = scan.beam_angle(i) - grid.origin.yaw
        if abs(dx * math.sin(a) - dy * math.cos(a)) <= 0.5 * math.sqrt(2):
            return True
    return False
