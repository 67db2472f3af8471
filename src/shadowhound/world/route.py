"""A route for the robot's body on its belief: the planned path, refusals that name the cause,
and, for a goal inside an object's clearance, the nearest point the body can stand on."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import PlanError
from .grid import Cell
from .legs import blocker_near
from .objects import Belief
from .planner import Path, plan_path, require_finite

GOAL_TOLERANCE = 0.5  # metres a goal inside a clearance may move (Nav2's planner tolerance)


@dataclass(frozen=True)
class NearGoal:
    """Where to stand instead of a goal that lies inside something's clearance."""

    point: tuple[float, float]  # the nearest reachable point that keeps the body clear
    what: str  # what the goal lies in: "the charging dock", "an obstacle"
    moved: float  # metres from the goal


def near_goal(
    belief: Belief,
    start: tuple[float, float],
    goal: tuple[float, float],
    tolerance: float = GOAL_TOLERANCE,
) -> NearGoal | None:
    """None when the body can stand on `goal`; else the nearest free cell within `tolerance`
    that a path from `start` reaches (as Nav2's planner tolerance does). Raises PlanError when
    the goal is off the map, in unmapped space, or nothing is free and reachable within reach
    (the message names what blocks it)."""
    require_finite(start, goal)
    grid, inflated = belief.grid, belief.inflated
    cell = grid.cell_of(*goal)
    if not grid.contains(cell) or not inflated.is_blocked(cell):
        return None
    what = blocker_near(belief, *goal)
    if what == "unmapped space":
        return None  # plan_route says so
    reach = int(math.ceil(tolerance / grid.resolution))
    near: list[tuple[float, Cell]] = []
    for dr in range(-reach, reach + 1):
        for dc in range(-reach, reach + 1):
            c = Cell(cell.col + dc, cell.row + dr)
            if inflated.is_blocked(c):
                continue
            d = math.dist(grid.center_of(c), goal)
            if d <= tolerance:
                near.append((d, c))
    for d, c in sorted(near, key=lambda n: n[0])[:12]:  # the nearest few: most share a path
        point = grid.center_of(c)
        try:
            plan_path(inflated, start, point)
        except PlanError:
            continue
        return NearGoal(point, what, d)
    return None  # plan_route refuses it, naming what blocks it


def plan_route(belief: Belief, start: tuple[float, float], goal: tuple[float, float]) -> Path:
    """The shortest safe path from `start` to `goal` (see `plan_path`). Raises PlanError; when
    the goal itself is blocked the message names what blocks it: "the goal (3.00, 2.00) is
    inside the blue box's clearance (0.35 m kept for the body)"."""
    inflated = belief.inflated
    grid = belief.grid
    require_finite(start, goal)
    cell = grid.cell_of(*goal)
    if grid.contains(cell) and inflated.is_blocked(cell):
        what = blocker_near(belief, *goal)
        where = f"the goal ({goal[0]:.2f}, {goal[1]:.2f})"
        if what == "unmapped space":
            raise PlanError(f"{where} is in unmapped space")
        owner = f"{what}'s" if what != "an obstacle" else "an obstacle's"
        raise PlanError(
            f"{where} is inside {owner} clearance ({belief.robot_radius:.2f} m kept for the body)"
        )
    return plan_path(inflated, start, goal)


def place_problem(belief: Belief, start: tuple[float, float], point: tuple[float, float]) -> str:
    """Why the body cannot reach `point` (a place) from `start` on this map, "" when it can
    (on the point itself, or within `GOAL_TOLERANCE` of it when the point lies inside
    something's clearance)."""
    try:
        near = near_goal(belief, start, point)
        plan_route(belief, start, near.point if near is not None else point)
    except PlanError as exc:
        return str(exc)
    return ""
