"""Geofence geometry: does a straight leg keep the robot's body inside the fence?

Pure Python, no dependencies. A fence is a circle around the odom origin (`CircleFence`) or a
simple polygon (`PolygonFence`, validated by `polygon_problem`). The robot's body is a circle of
radius `margin` around the centre of the robot, so a leg keeps the body inside exactly when the
centre keeps a clearance of at least `margin` from the fence's boundary all along it.

`leg_breach` applies the one rule every fence shares (see its docstring). Boundary cases are
decided on purpose, not by accident of floating point: a centre on an edge or a vertex is
inside the closed fence, and a leg is cut at every point where it meets an edge, so a leg that
only touches the polygon at vertices, or runs along an edge, is judged piece by piece.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from typing import Protocol

Point = tuple[float, float]

# Metres. Far below any distance that matters for a 70 cm robot, far above float round-off
# for coordinates up to a few kilometres.
EPS = 1e-9
MAX_VERTICES = 1000
_BISECTIONS = 60  # halves a leg of up to 1 km below 1e-15 m


class BreachKind(Enum):
    STARTS_OUTSIDE = "starts outside"  # the leg's start is already outside the fence
    LEAVES = "leaves"  # the centre of the robot crosses the fence
    TOO_CLOSE = "too close"  # the body (margin) reaches the fence, the centre stays inside
    STAYS_NEAR = "stays near"  # a leg starting within the margin does not walk back out of it


@dataclass(frozen=True)
class Breach:
    """Where a leg first breaks the fence rule, and how."""

    kind: BreachKind
    at: Point  # the first point of the leg (the robot's centre) that breaks the rule
    start_clearance: float  # signed: + inside, - outside the fence, at the leg's start
    exit: Point | None = None  # where the centre itself leaves the fence, if it does


class Fence(Protocol):
    def clearance(self, p: Point) -> float:
        """Signed distance from p to the boundary: + inside, 0 on it, - outside."""
        ...

    def first_below(self, a: Point, b: Point, need: float) -> float | None:
        """The first t in [0, 1] where a + t (b - a) has clearance < need - EPS, or None."""
        ...


def leg_breach(fence: Fence, a: Point, b: Point, margin: float) -> Breach | None:
    """Check the straight leg a -> b of the robot's centre. None when it keeps the rule:

    Every point of the leg keeps a clearance of at least `margin` from the boundary. A leg that
    starts closer than `margin` (the robot stopped a little inside it, or was put there) may
    still turn in place, or walk back to a clearance of `margin` without ever coming closer
    than it already is. A leg that starts outside the fence is refused.
    """
    start = fence.clearance(a)
    if start < -EPS:
        return Breach(BreachKind.STARTS_OUTSIDE, a, start, a)
    need = max(0.0, min(margin, start))
    t = fence.first_below(a, b, need)
    if t is not None:
        leaves = t if need == 0 else fence.first_below(a, b, 0.0)
        kind = BreachKind.LEAVES if need == 0 else BreachKind.TOO_CLOSE
        return Breach(kind, _at(a, b, t), start, None if leaves is None else _at(a, b, leaves))
    if start < margin - EPS and _dist(a, b) > EPS and fence.clearance(b) < margin - EPS:
        return Breach(BreachKind.STAYS_NEAR, b, start)
    return None


@dataclass(frozen=True)
class CircleFence:
    """Everything within `radius` metres of the odom origin."""

    radius: float

    def clearance(self, p: Point) -> float:
        return self.radius - math.hypot(p[0], p[1])

    def first_below(self, a: Point, b: Point, need: float) -> float | None:
        reach = self.radius - need + EPS  # the centre may be at most this far from the origin
        if math.hypot(a[0], a[1]) > reach:
            return 0.0
        if math.hypot(b[0], b[1]) <= reach:
            return None  # a disc is convex: both ends inside means the whole leg is
        # |a + t d| = reach has one root in (0, 1]: the leg leaves the disc there.
        dx, dy = b[0] - a[0], b[1] - a[1]
        qa = dx * dx + dy * dy
        qb = 2 * (a[0] * dx + a[1] * dy)
        qc = a[0] * a[0] + a[1] * a[1] - reach * reach
        root = (-qb + math.sqrt(max(0.0, qb * qb - 4 * qa * qc))) / (2 * qa)
        return min(1.0, max(0.0, root))


class PolygonFence:
    """Everything inside a simple polygon, its edges and vertices included."""

    def __init__(self, vertices: Sequence[Point]) -> None:
        self.vertices = [(float(x), float(y)) for x, y in vertices]
        n = len(self.vertices)
        self.edges = [(self.vertices[i], self.vertices[(i + 1) % n]) for i in range(n)]

    def boundary_distance(self, p: Point) -> float:
        return min(_point_segment_distance(p, e0, e1) for e0, e1 in self.edges)

    def contains(self, p: Point) -> bool:
        """Inside or on the boundary (within EPS)."""
        return self.boundary_distance(p) <= EPS or _even_odd(p, self.vertices)

    def clearance(self, p: Point) -> float:
        d = self.boundary_distance(p)
        if d <= EPS:
            return 0.0
        return d if _even_odd(p, self.vertices) else -d

    def first_below(self, a: Point, b: Point, need: float) -> float | None:
        if self.clearance(a) < need - EPS:
            return 0.0
        if need <= EPS:
            return self._first_outside(a, b)
        # The start keeps `need` > 0, so before the centre can leave, it must come within
        # `need` of an edge: the first such point over all edges is the answer.
        hits = [
            t for e0, e1 in self.edges if (t := _first_within(a, b, e0, e1, need - EPS)) is not None
        ]
        return min(hits, default=None)

    def _first_outside(self, a: Point, b: Point) -> float | None:
        """Cut the leg wherever it meets an edge; each piece between cuts is then wholly
        inside or wholly outside (or on an edge), so its midpoint decides it."""
        cuts = {0.0, 1.0}
        for e0, e1 in self.edges:
            cuts.update(_meet(a, b, e0, e1))
        ts = sorted(cuts)
        for t0, t1 in zip(ts, ts[1:], strict=False):
            mid = _at(a, b, (t0 + t1) / 2)
            if not self.contains(mid):
                return t0
        return None if self.contains(b) else 1.0


def polygon_problem(vertices: Sequence[Point]) -> str:
    """Why these vertices are not a usable fence ("" when they are): 3 to MAX_VERTICES finite
    points, no repeated consecutive point, no two edges that cross or touch (other than
    neighbours at their shared vertex), and a non-zero area."""
    n = len(vertices)
    if n < 3:
        return f"it has {n} vertices; at least 3 are needed"
    if n > MAX_VERTICES:
        return f"it has {n} vertices; at most {MAX_VERTICES} are allowed (checks cost n squared)"
    for i, (x, y) in enumerate(vertices):
        if not (math.isfinite(x) and math.isfinite(y)):
            return f"vertex {i} ({x}, {y}) is not a finite point"
    pts = [(float(x), float(y)) for x, y in vertices]
    for i in range(n):
        if _dist(pts[i], pts[(i + 1) % n]) <= EPS:
            return f"vertices {i} and {(i + 1) % n} are the same point {_fmt(pts[i])}"
    far = max(pts, key=lambda p: _dist(pts[0], p))
    if all(_point_line_distance(p, pts[0], far) <= EPS for p in pts):
        return "it has zero area: all its vertices lie on one line"
    edges = [(pts[i], pts[(i + 1) % n]) for i in range(n)]
    for i in range(n):
        for j in range(i + 1, n):
            neighbours = j == i + 1 or (i == 0 and j == n - 1)
            (p0, p1), (q0, q1) = edges[i], edges[j]
            if neighbours:
                shared = p1 if j == i + 1 else p0
                other_p = p0 if shared == p1 else p1
                other_q = q1 if shared == q0 else q0
                # Neighbours may only share their common vertex: folding back overlaps them.
                if (
                    _point_segment_distance(other_q, p0, p1) <= EPS
                    or _point_segment_distance(other_p, q0, q1) <= EPS
                ):
                    return (
                        f"edges {i} and {j} fold back on each other at "
                        f"{_fmt(shared)}: the polygon must not cross or touch itself"
                    )
            elif _segment_distance(p0, p1, q0, q1) <= EPS:
                return (
                    f"edges {i} {_fmt(p0)}-{_fmt(p1)} and {j} {_fmt(q0)}-{_fmt(q1)} "
                    "cross or touch: the polygon must not cross or touch itself"
                )
    area = abs(sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in edges)) / 2
    if area <= 1e-6:
        return f"its area is {area:.2g} square metres, too small to stand in"
    return ""


# -- geometry ---------------------------------------------------------------------------------


def _fmt(p: Point) -> str:
    return f"({p[0]:g}, {p[1]:g})"


def _at(a: Point, b: Point, t: float) -> Point:
    return (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))


def _dist(p: Point, q: Point) -> float:
    return math.hypot(q[0] - p[0], q[1] - p[1])


def _cross(o: Point, p: Point, q: Point) -> float:
    return (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])


def _project(p: Point, a: Point, b: Point) -> float:
    """Parameter in [0, 1] of the point of segment a-b nearest to p."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    if length2 == 0:
        return 0.0
    return min(1.0, max(0.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))


def _point_line_distance(p: Point, a: Point, b: Point) -> float:
    return abs(_cross(a, b, p)) / _dist(a, b)


def _point_segment_distance(p: Point, a: Point, b: Point) -> float:
    return _dist(p, _at(a, b, _project(p, a, b)))


def _even_odd(p: Point, vertices: Sequence[Point]) -> bool:
    """Ray casting; only meaningful for points off the boundary."""
    x, y = p
    inside = False
    n = len(vertices)
    for i in range(n):
        (x1, y1), (x2, y2) = vertices[i], vertices[(i + 1) % n]
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def _meet(a: Point, b: Point, e0: Point, e1: Point) -> list[float]:
    """Parameters t on the leg a-b where it meets the edge e0-e1: a crossing, a touch at a
    vertex, or both ends of a stretch along the edge."""
    d = (b[0] - a[0], b[1] - a[1])
    f = (e1[0] - e0[0], e1[1] - e0[1])
    length = math.hypot(*d)
    if length <= EPS:
        return []
    ts = []
    for vertex in (e0, e1):  # the leg passes through an end of the edge
        t = _project(vertex, a, b)
        if _dist(_at(a, b, t), vertex) <= EPS:
            ts.append(t)
    for t in (0.0, 1.0):  # an end of the leg lies on the edge
        if _point_segment_distance(_at(a, b, t), e0, e1) <= EPS:
            ts.append(t)
    denominator = f[0] * d[1] - f[1] * d[0]
    if abs(denominator) > 1e-12 * length * math.hypot(*f):  # not parallel: a crossing?
        t = (f[0] * (e0[1] - a[1]) - f[1] * (e0[0] - a[0])) / denominator
        if -EPS <= t <= 1 + EPS and _point_segment_distance(_at(a, b, t), e0, e1) <= EPS:
            ts.append(min(1.0, max(0.0, t)))
    return ts


def _segment_distance(p0: Point, p1: Point, q0: Point, q1: Point) -> float:
    """Shortest distance between two segments (0 when they cross or touch)."""
    if _proper_cross(p0, p1, q0, q1):
        return 0.0
    return min(
        _point_segment_distance(p0, q0, q1),
        _point_segment_distance(p1, q0, q1),
        _point_segment_distance(q0, p0, p1),
        _point_segment_distance(q1, p0, p1),
    )


def _proper_cross(p0: Point, p1: Point, q0: Point, q1: Point) -> bool:
    d1, d2 = _cross(q0, q1, p0), _cross(q0, q1, p1)
    d3, d4 = _cross(p0, p1, q0), _cross(p0, p1, q1)
    return ((d1 > 0 > d2) or (d1 < 0 < d2)) and ((d3 > 0 > d4) or (d3 < 0 < d4))


def _first_within(a: Point, b: Point, e0: Point, e1: Point, need: float) -> float | None:
    """The first t where the leg's point is closer than `need` to the edge e0-e1, or None.

    The distance from a point moving along a line to a fixed segment is convex in t, so the
    points closer than `need` form one interval: find its nearest point, then bisect."""

    def gap(t: float) -> float:
        return _point_segment_distance(_at(a, b, t), e0, e1)

    if gap(0.0) < need:
        return 0.0
    t_near = _nearest_t(a, b, e0, e1)
    if gap(t_near) >= need:
        return None
    lo, hi = 0.0, t_near  # gap(lo) >= need > gap(hi)
    for _ in range(_BISECTIONS):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if gap(mid) >= need else (lo, mid)
    return hi


def _nearest_t(a: Point, b: Point, e0: Point, e1: Point) -> float:
    """The t in [0, 1] where the leg comes nearest to the edge: where they cross, or where
    an end of one is nearest to the other (the minimum of two segments' distance is there)."""
    if _dist(a, b) <= EPS:
        return 0.0
    cross = _meet(a, b, e0, e1)
    candidates = [*cross, 0.0, 1.0, _project(e0, a, b), _project(e1, a, b)]
    return min(candidates, key=lambda t: (_point_segment_distance(_at(a, b, t), e0, e1), t))
