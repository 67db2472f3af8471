"""Paths around obstacles: A* on the inflated grid, then shortcuts along lines of sight.

A* searches 8-connected cells (diagonal steps only where both side cells are free, so no step
cuts a blocked corner) with the octile-distance heuristic, which is exact on open ground: the
result is a shortest 8-connected path. Shortcutting then replaces runs of cells by straight
segments wherever the segment crosses only free cells (a supercover walk: every cell the
segment touches, both cells at a corner). Shortcuts only ever make the path shorter, so it is
never longer than the optimal 8-connected path (itself up to about 8 % longer than the best
any-angle path), and every point of it lies in unblocked cells: by the inflation rule the body
keeps its radius from every occupied cell.

Long because: it is one search. A*, its jump-point expansion (`_JumpGrid`), the escape from a
start inside a clearance zone and the line-of-sight shortcuts all walk the same inflated grid
in the same cell indexing, and the optimality argument above holds only for them together.
"""

from __future__ import annotations

import heapq
import math
from collections import deque
from dataclasses import dataclass

from ..errors import PlanError
from ..state import not_finite
from .grid import OCCUPIED_THRESHOLD, Cell
from .inflation import InflatedGrid

_SQRT2 = math.sqrt(2.0)
_ESCAPE_LIMIT = 1.0  # metres the start may lie inside a clearance zone and still be left


@dataclass(frozen=True)
class Path:
    """A planned path in the map frame: straight legs between `waypoints` (start first)."""

    waypoints: tuple[tuple[float, float], ...]
    length: float  # metres along the legs
    grid_length: float  # metres of the 8-connected cell path before shortcuts
    expanded: int  # cells A* expanded: the search's effort
    escaped: bool = False  # the start lay in a clearance zone; the first leg leaves it

    def to_dict(self) -> dict[str, object]:
        return {
            "length": round(self.length, 3),
            "waypoints": [[round(x, 3), round(y, 3)] for x, y in self.waypoints],
        }


def require_finite(start: tuple[float, float], goal: tuple[float, float]) -> None:
    """Raise PlanError when the start or the goal is not finite numbers: no cell holds it."""
    for what, (x, y) in (("goal", goal), ("start", start)):
        if bad := not_finite(x=x, y=y):
            raise PlanError(f"the {what} is not a point on the map: it is not finite ({bad})")


def plan_path(
    inflated: InflatedGrid, start: tuple[float, float], goal: tuple[float, float]
) -> Path:
    """The shortest safe path from `start` to `goal` (map-frame points). Raises PlanError."""
    require_finite(start, goal)
    grid = inflated.grid
    s_cell, g_cell = grid.cell_of(*start), grid.cell_of(*goal)
    if not grid.contains(g_cell):
        raise PlanError(f"the goal ({goal[0]:.2f}, {goal[1]:.2f}) is outside the map")
    if inflated.is_blocked(g_cell):
        why = _why_blocked(inflated, g_cell)
        raise PlanError(f"the goal ({goal[0]:.2f}, {goal[1]:.2f}) is {why}")
    if not grid.contains(s_cell):
        raise PlanError(f"the start ({start[0]:.2f}, {start[1]:.2f}) is outside the map")
    escaped = False
    if inflated.is_blocked(s_cell):
        s_cell = _escape(inflated, s_cell)
        escaped = True
    cells, expanded = _astar(inflated, s_cell, g_cell)
    grid_length = _cells_length(cells) * grid.resolution
    pts = [_grid_point(inflated, c) for c in _corners(cells)]
    pts = _shortcut(inflated, pts)
    # The exact start and goal replace their cells' centres when the straight legs to them
    # stay clear; otherwise the centres are kept (a leg between centres was checked).
    if len(pts) == 1:
        pts.append(pts[0])
    s_gf, g_gf = _gf(inflated, start), _gf(inflated, goal)
    if not escaped and _clear(inflated, s_gf, pts[1]):
        pts[0] = s_gf
    if _clear(inflated, pts[-2], g_gf):
        pts[-1] = g_gf
    waypoints = [_map_point(inflated, p) for p in pts]
    if escaped:
        waypoints.insert(0, start)
    length = sum(math.dist(a, b) for a, b in zip(waypoints, waypoints[1:], strict=False))
    return Path(tuple(waypoints), length, grid_length, expanded, escaped)


def line_is_clear(inflated: InflatedGrid, a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Whether the straight segment between two map-frame points crosses only free cells."""
    return _clear(inflated, _gf(inflated, a), _gf(inflated, b))


# -- search -------------------------------------------------------------------------------


def _astar(inflated: InflatedGrid, start: Cell, goal: Cell) -> tuple[list[Cell], int]:
    """A* over jump points: returns the corner cells of a shortest 8-connected path."""
    jumps = _JumpGrid(inflated, goal)
    pw = jumps.pw
    s = (start.row + 1) * pw + start.col + 1
    g = jumps.goal
    gr, gc = divmod(g, pw)
    k = _SQRT2 - 2.0
    cost = {s: 0.0}
    parent = {s: -1}
    closed: set[int] = set()
    heap = [(0.0, 0.0, s)]
    expanded = 0
    while heap:
        _, _, cur = heapq.heappop(heap)
        if cur in closed:
            continue
        if cur == g:
            break
        closed.add(cur)
        expanded += 1
        base = cost[cur]
        cr, cc = divmod(cur, pw)
        for step in jumps.directions(cur, parent[cur]):
            nxt = jumps.jump(cur, step)
            if nxt < 0 or nxt in closed:
                continue
            r, c = divmod(nxt, pw)
            ax, ay = abs(c - cc), abs(r - cr)
            ng = base + ax + ay + k * (ax if ax < ay else ay)
            if ng < cost.get(nxt, math.inf):
                cost[nxt] = ng
                parent[nxt] = cur
                dx, dy = abs(c - gc), abs(r - gr)
                hh = dx + dy + k * (dx if dx < dy else dy)
                heapq.heappush(heap, (ng + hh, hh, nxt))
    else:
        raise PlanError(
            "no collision-free path: every way to the goal passes closer than "
            f"{inflated.radius:.2f} m to an obstacle or through unmapped space"
        )
    cells = []
    cur = g
    while cur != -1:
        r, c = divmod(cur, pw)
        cells.append(Cell(c - 1, r - 1))
        cur = parent[cur]
    cells.reverse()
    return cells, expanded


class _JumpGrid:
    """Jump point search (Harabor and Grastien 2011) without corner cutting, on byte masks.

    The grid gets a one-cell blocked border. A straight jump ends at the first blocked cell,
    the goal, or a cell with a forced neighbour (a side cell that opens up after being
    blocked); `forced_*` masks mark those cells per direction, built once with big-integer
    shifts (one byte per cell), so a straight jump is two C-level `find`s. Vertical jumps use
    column-major copies of the masks.
    """

    def __init__(self, inflated: InflatedGrid, goal: Cell) -> None:
        grid = inflated.grid
        w, h = grid.width, grid.height
        pw, ph = w + 2, h + 2
        self.pw, self.ph = pw, ph
        blocked = bytearray(b"\x01") * (pw * ph)
        src = inflated.blocked
        for row in range(h):
            blocked[(row + 1) * pw + 1 : (row + 1) * pw + 1 + w] = src[row * w : (row + 1) * w]
        self.blocked = bytes(blocked)
        self.goal = (goal.row + 1) * pw + goal.col + 1
        n = pw * ph
        full = (1 << (8 * n)) - 1
        ones = int.from_bytes(b"\x01" * n, "big")
        b_int = int.from_bytes(self.blocked, "big")
        w_int = ones ^ b_int

        def at(x: int, k: int) -> int:  # value at cell i becomes the value at cell i - k
            return x >> (8 * k) if k >= 0 else (x << (-8 * k)) & full

        def to_bytes(x: int) -> bytes:
            return x.to_bytes(n, "big")

        def forced(k1: int, k2: int, k3: int, k4: int) -> bytes:
            # A side cell free here (offset k1 / k3) that was blocked one step back (k2 / k4).
            return to_bytes(at(w_int, k1) & at(b_int, k2) | at(w_int, k3) & at(b_int, k4))

        self.f_east = forced(pw, pw + 1, -pw, -pw + 1)
        self.f_west = forced(pw, pw - 1, -pw, -pw - 1)
        f_north = forced(1, pw + 1, -1, pw - 1)
        f_south = forced(1, -pw + 1, -1, -pw - 1)
        self.blocked_t = _transpose(self.blocked, pw, ph)
        self.f_north_t = _transpose(f_north, pw, ph)
        self.f_south_t = _transpose(f_south, pw, ph)

    def directions(self, cur: int, par: int) -> list[tuple[int, int]]:
        """(dx, dy) to search from `cur`, pruned by the direction it was reached from."""
        b, pw = self.blocked, self.pw
        if par < 0:
            out = [
                (dx, dy)
                for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1))
                if not b[cur + dx + dy * pw]
            ]
            out += [
                (dx, dy)
                for dx in (1, -1)
                for dy in (1, -1)
                if not (b[cur + dx + dy * pw] or b[cur + dx] or b[cur + dy * pw])
            ]
            return out
        pr, pc = divmod(par, pw)
        cr, cc = divmod(cur, pw)
        dx = (cc > pc) - (cc < pc)
        dy = (cr > pr) - (cr < pr)
        out = []
        if dx and dy:
            side_y, side_x = not b[cur + dy * pw], not b[cur + dx]
            if side_y:
                out.append((0, dy))
            if side_x:
                out.append((dx, 0))
            if side_y and side_x:
                out.append((dx, dy))
        elif dx:
            nxt, up, down = not b[cur + dx], not b[cur + pw], not b[cur - pw]
            if nxt:
                out.append((dx, 0))
                if up:
                    out.append((dx, 1))
                if down:
                    out.append((dx, -1))
            if up:
                out.append((0, 1))
            if down:
                out.append((0, -1))
        else:
            nxt, right, left = not b[cur + dy * pw], not b[cur + 1], not b[cur - 1]
            if nxt:
                out.append((0, dy))
                if right:
                    out.append((1, dy))
                if left:
                    out.append((-1, dy))
            if right:
                out.append((1, 0))
            if left:
                out.append((-1, 0))
        return out

    def jump(self, cur: int, step: tuple[int, int]) -> int:
        """The next jump point from `cur` in direction `step`, or -1."""
        dx, dy = step
        pw = self.pw
        if dx and dy:
            b = self.blocked
            i = cur + dx + dy * pw
            while True:
                if b[i]:
                    return -1
                if (
                    i == self.goal
                    or self._straight(i + dx, dx, 0) >= 0
                    or self._straight(i + dy * pw, 0, dy) >= 0
                ):
                    return i
                if b[i + dx] or b[i + dy * pw]:
                    return -1
                i += dx + dy * pw
        return self._straight(cur + dx + dy * pw, dx, dy)

    def _straight(self, i: int, dx: int, dy: int) -> int:
        """A horizontal or vertical jump whose first cell is `i`: its jump point or -1."""
        pw, ph, goal = self.pw, self.ph, self.goal
        row, col = divmod(i, pw)
        if dx:
            start = row * pw
            if dx > 0:
                stop = self.blocked.find(1, i, start + pw)
                forced = self.f_east.find(1, i, stop)
                if row * pw <= goal < stop and goal >= i and (forced < 0 or goal <= forced):
                    return goal
                return forced
            stop = self.blocked.rfind(1, start, i + 1)
            forced = self.f_west.rfind(1, stop + 1, i + 1)
            if stop < goal <= i and goal < start + pw and (forced < 0 or goal >= forced):
                return goal
            return forced
        ti = col * ph + row  # the same cell in the column-major copies
        start = col * ph
        g_row, g_col = divmod(goal, pw)
        tg = g_col * ph + g_row
        if dy > 0:
            stop = self.blocked_t.find(1, ti, start + ph)
            forced = self.f_north_t.find(1, ti, stop)
            if g_col == col and ti <= tg < stop and (forced < 0 or tg <= forced):
                return goal
        else:
            stop = self.blocked_t.rfind(1, start, ti + 1)
            forced = self.f_south_t.rfind(1, stop + 1, ti + 1)
            if g_col == col and stop < tg <= ti and (forced < 0 or tg >= forced):
                return goal
        if forced < 0:
            return -1
        f_col, f_row = divmod(forced, ph)
        return f_row * pw + f_col


def _transpose(data: bytes, width: int, height: int) -> bytes:
    """Row-major `height` x `width` bytes to column-major (one extended slice per column)."""
    return b"".join(data[c::width] for c in range(width))


def _escape(inflated: InflatedGrid, start: Cell) -> Cell:
    """The nearest unblocked cell reachable from a start inside a clearance zone, walking only
    through cells that are not themselves occupied (the body may back out, never pass through)."""
    grid = inflated.grid
    limit = math.ceil(_ESCAPE_LIMIT / grid.resolution)
    seen = {start}
    queue = deque([start])
    while queue:
        cell = queue.popleft()
        if not inflated.is_blocked(cell):
            return cell
        for dc, dr in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            nxt = Cell(cell.col + dc, cell.row + dr)
            if (
                nxt in seen
                or not grid.contains(nxt)
                or abs(nxt.col - start.col) > limit
                or abs(nxt.row - start.row) > limit
                or grid.value(nxt) >= OCCUPIED_THRESHOLD
            ):
                continue
            seen.add(nxt)
            queue.append(nxt)
    raise PlanError(
        f"the robot is boxed in: no free space within {_ESCAPE_LIMIT:.1f} m keeps "
        f"{inflated.radius:.2f} m from obstacles"
    )


def _why_blocked(inflated: InflatedGrid, cell: Cell) -> str:
    v = inflated.grid.value(cell)
    if v >= OCCUPIED_THRESHOLD:
        return "inside an obstacle"
    if v < 0 and not inflated.unknown_is_free:
        return "in unmapped space"
    return f"closer than {inflated.radius:.2f} m to an obstacle"


# -- geometry on cells ----------------------------------------------------------------------


def _cells_length(cells: list[Cell]) -> float:
    """Length in cells of the 8-connected path through these corners (octile distances)."""
    total = 0.0
    for a, b in zip(cells, cells[1:], strict=False):
        dx, dy = abs(a.col - b.col), abs(a.row - b.row)
        total += max(dx, dy) + (_SQRT2 - 1.0) * min(dx, dy)
    return total


def _corners(cells: list[Cell]) -> list[Cell]:
    """The cells where the path changes direction, with both ends."""
    if len(cells) <= 2:
        return list(cells)
    out = [cells[0]]
    for prev, cur, nxt in zip(cells, cells[1:], cells[2:], strict=False):
        if (cur.col - prev.col, cur.row - prev.row) != (nxt.col - cur.col, nxt.row - cur.row):
            out.append(cur)
    out.append(cells[-1])
    return out


def _grid_point(inflated: InflatedGrid, cell: Cell) -> tuple[float, float]:
    return (cell.col + 0.5, cell.row + 0.5)


def _map_point(inflated: InflatedGrid, p: tuple[float, float]) -> tuple[float, float]:
    grid = inflated.grid
    gx, gy = p[0] * grid.resolution, p[1] * grid.resolution
    c, s = math.cos(grid.origin.yaw), math.sin(grid.origin.yaw)
    return (grid.origin.x + gx * c - gy * s, grid.origin.y + gx * s + gy * c)


def _gf(inflated: InflatedGrid, p: tuple[float, float]) -> tuple[float, float]:
    return inflated.grid.to_grid_frame(*p)


def _shortcut(inflated: InflatedGrid, pts: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Greedy string pulling: from each kept point, go on to the last point still in sight."""
    if len(pts) <= 2:
        return pts
    out = [pts[0]]
    i = 0
    while i < len(pts) - 1:
        j = i + 1
        while j + 1 < len(pts) and _clear(inflated, pts[i], pts[j + 1]):
            j += 1
        out.append(pts[j])
        i = j
    return out


def _clear(inflated: InflatedGrid, a: tuple[float, float], b: tuple[float, float]) -> bool:
    """Supercover walk from a to b (grid-frame points): False if any touched cell is blocked."""
    grid = inflated.grid
    w, h = grid.width, grid.height
    blocked = inflated.blocked
    x0, y0 = a
    x1, y1 = b
    c, r = math.floor(x0), math.floor(y0)
    ce, re_ = math.floor(x1), math.floor(y1)

    def bad(col: int, row: int) -> bool:
        return not (0 <= col < w and 0 <= row < h) or blocked[row * w + col] == 1

    if bad(c, r):
        return False
    dx, dy = x1 - x0, y1 - y0
    sx = 1 if dx > 0 else -1
    sy = 1 if dy > 0 else -1
    # Segment parameter (0 at a, 1 at b) at which the walk next crosses a column / row line.
    t_dx = abs(1.0 / dx) if dx else math.inf
    t_dy = abs(1.0 / dy) if dy else math.inf
    t_x = ((c + 1 - x0) if dx > 0 else (x0 - c)) * t_dx if dx else math.inf
    t_y = ((r + 1 - y0) if dy > 0 else (y0 - r)) * t_dy if dy else math.inf
    for _ in range(abs(ce - c) + abs(re_ - r) + 4):
        if min(t_x, t_y) > 1.0 + 1e-9:
            return True  # the segment ends inside the current cell
        if abs(t_x - t_y) < 1e-9:
            # Through a corner (or within rounding of one): every cell around it is touched.
            if bad(c + sx, r) or bad(c, r + sy):
                return False
            c += sx
            r += sy
            t_x += t_dx
            t_y += t_dy
        elif t_x < t_y:
            c += sx
            t_x += t_dx
        else:
            r += sy
            t_y += t_dy
        if bad(c, r):
            return False
    return False  # more crossings than the segment can have: rounding trouble, so refuse
