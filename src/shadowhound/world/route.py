"""A route for the robot's body on its belief: the planned path, refusals that name the cause."""

from __future__ import annotations

from ..errors import PlanError
from .legs import blocker_near
from .objects import Belief
from .planner import Path, plan_path, require_finite


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
