"""Where to stand to look at an object: a free, reachable point near it, facing it."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import PlanError
from ..state import Pose2D
from .objects import Belief, KnownObject, object_key
from .planner import Path, plan_path, require_finite

DEFAULT_STANDOFF = 0.6  # metres between the object's surface and the robot's centre
PERSON_STANDOFF = 1.0  # metres: the least a person is given, whatever the standoff asked
# Metres more than that aimed at: what a sighting (a camera box ranged by a scan) and the stop
# may be off by. Aimed at exactly, the least is broken whenever they err towards the person.
PERSON_MARGIN = 0.05
_PEOPLE = frozenset({"person", "people", "man", "woman", "child", "kid", "boy", "girl", "human"})
_STEP_DEG = 15


@dataclass(frozen=True)
class Standoff:
    """A pose `gap` metres from the object's surface, facing its centre, and the path there."""

    pose: Pose2D
    path: Path


def is_person(target: KnownObject) -> bool:
    """Whether the object is a person ("person", "the tall man"): by the last word of its name."""
    words = object_key(target.name).split()
    return bool(words) and words[-1] in _PEOPLE


def standoff_point(
    belief: Belief,
    start: tuple[float, float],
    target: KnownObject,
    gap: float = DEFAULT_STANDOFF,
) -> Standoff:
    """The reachable standoff nearest the robot's side of the object (tried every 15 degrees,
    starting with the direction towards `start`). A person is given at least PERSON_STANDOFF,
    with PERSON_MARGIN to spare. Raises PlanError when none is reachable."""
    if not (math.isfinite(gap) and gap > 0):
        raise ValueError(f"standoff gap must be > 0 metres, got {gap}")
    if is_person(target):
        gap = max(gap, PERSON_STANDOFF + PERSON_MARGIN)
    require_finite(start, (target.x, target.y))
    reach = target.radius + max(gap, belief.robot_radius)
    towards = math.atan2(start[1] - target.y, start[0] - target.x)
    offsets = [0] + [s * k for k in range(_STEP_DEG, 181, _STEP_DEG) for s in (1, -1)]
    last_error: PlanError | None = None
    for deg in offsets[:-1]:  # +180 and -180 are the same point
        a = towards + math.radians(deg)
        x, y = target.x + reach * math.cos(a), target.y + reach * math.sin(a)
        if not belief.inflated.is_free_at(x, y):
            continue
        try:
            path = plan_path(belief.inflated, start, (x, y))
        except PlanError as exc:
            last_error = exc
            continue
        facing = math.atan2(target.y - y, target.x - x)
        return Standoff(Pose2D(x, y, facing), path)
    why = f": {last_error}" if last_error else ": every point around it is blocked"
    raise PlanError(f"no reachable place {gap:.1f} m from {target.the_name}{why}")
