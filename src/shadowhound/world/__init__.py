"""The robot's belief about its world: occupancy grid, known objects, paths and checks.

Pure Python (standard library only), importable without ROS. The simulator's ground truth
lives in `robot/`; this package only holds what the robot has been told or has sensed.
"""

from ..errors import GridError, PlanError
from .grid import (
    DEFAULT_RESOLUTION,
    FREE,
    OCCUPIED,
    OCCUPIED_THRESHOLD,
    UNKNOWN,
    Cell,
    OccupancyGrid,
)
from .inflation import DEFAULT_ROBOT_RADIUS, InflatedGrid, inflate
from .legs import LegCheck, blocker_near, check_leg
from .objects import Belief, KnownObject, merge_sightings, object_key
from .planner import Path, line_is_clear, plan_path
from .route import GOAL_TOLERANCE, NearGoal, near_goal, place_problem, plan_route
from .scan_update import apply_scan
from .search import Coverage, Viewpoint
from .standoff import DEFAULT_STANDOFF, Standoff, standoff_point

__all__ = [
    "DEFAULT_RESOLUTION",
    "DEFAULT_ROBOT_RADIUS",
    "DEFAULT_STANDOFF",
    "GOAL_TOLERANCE",
    "FREE",
    "OCCUPIED",
    "OCCUPIED_THRESHOLD",
    "UNKNOWN",
    "Belief",
    "Cell",
    "Coverage",
    "GridError",
    "InflatedGrid",
    "KnownObject",
    "LegCheck",
    "NearGoal",
    "OccupancyGrid",
    "Path",
    "PlanError",
    "Standoff",
    "Viewpoint",
    "apply_scan",
    "blocker_near",
    "check_leg",
    "inflate",
    "line_is_clear",
    "merge_sightings",
    "near_goal",
    "place_problem",
    "object_key",
    "plan_path",
    "plan_route",
    "standoff_point",
]
