"""The rules every walked path obeys, in one place: the step limit per straight leg, the
geofences (with the body's margin) and, with a map, nothing in the way.

The safety governor checks every predicted path with `path_problems`; skills that choose a
new path while they run (nav.goto re-planning around an obstacle, a search's viewpoints, an
object's approach) check it here too before walking it, with the same words.
"""

from __future__ import annotations

import math

from .. import geofence
from ..config import SafetyConfig
from ..state import Pose2D
from ..world import check_leg
from .bounds import fences
from .context import PlanEnv


def path_problems(
    lim: SafetyConfig, pose: Pose2D, poses: list[Pose2D], env: PlanEnv, what: str
) -> list[str]:
    """Why the straight legs from `pose` through `poses` may not be walked: the step limit
    (per straight leg), the geofences and, with a map, anything in the way. Skills that
    re-plan on the way (nav.goto) check their new path here too."""
    reasons: list[str] = []
    for leg in legs(pose, poses):
        if leg > lim.max_step_distance + 1e-9:
            reasons.append(
                f"a straight leg of {leg:.2f} m exceeds the limit of "
                f"{lim.max_step_distance:g} m per step (safety.max_step_distance)"
            )
            break
    outside = _outside_fence(lim, pose, poses)
    if outside:
        reasons.append(outside)
    reasons += _in_the_way(what, pose, poses, env)
    return reasons


def _outside_fence(lim: SafetyConfig, pose: Pose2D, poses: list[Pose2D]) -> str:
    """Why the path from `pose` through `poses` breaks a geofence ("" when it does not).
    The robot's body is a circle of safety.geofence_margin around its centre."""
    margin, every = lim.geofence_margin, fences(lim)
    previous = pose
    for p in poses:
        a, b = (previous.x, previous.y), (p.x, p.y)
        for fence, name, where in every:
            breach = geofence.leg_breach(fence, a, b, margin)
            if breach is not None:
                return _fence_message(breach, a, b, (name, where), margin)
        previous = p
    return ""


def _in_the_way(what: str, pose: Pose2D, poses: list[Pose2D], env: PlanEnv) -> list[str]:
    """With a map, every straight leg of a moving step must stay in mapped free space, the body
    clear of everything on it: "nav.move 4 m: the red ball is in the way at 2.4 m"."""
    if env.belief is None:
        return []
    previous = pose
    for p in poses:
        leg = check_leg(env.belief, (previous.x, previous.y), (p.x, p.y))
        if not leg.clear:
            at = "" if len(poses) == 1 else f" (on its leg from {_xy((previous.x, previous.y))})"
            return [f"{what}: {leg.message()}{at}"]
        previous = p
    return []


def _fence_message(
    breach: geofence.Breach,
    a: tuple[float, float],
    b: tuple[float, float],
    fence: tuple[str, str],
    margin: float,
) -> str:
    """Say where the path first breaks the fence, and where its centre leaves it."""
    Kind = geofence.BreachKind
    name, full = fence[0], " ".join(fence)
    leg = f"its path from {_xy(a)} to {_xy(b)}"
    body = f"{margin:g} m kept around its centre for the robot's body (safety.geofence_margin)"
    if breach.kind is Kind.STARTS_OUTSIDE:
        return f"it would start at {_xy(a)}, outside {full}"
    if breach.kind is Kind.LEAVES:
        return f"{leg} leaves {full} at {_xy(breach.at)}"
    if breach.kind is Kind.STAYS_NEAR:
        return (
            f"{leg} starts {breach.start_clearance:.2f} m from the edge of {full}, within "
            f"the {body}: from there the robot may only turn in place, or walk back to at "
            f"least {margin:g} m from the edge, but this leg ends closer"
        )
    leaves = f"; its centre leaves {name} at {_xy(breach.exit)}" if breach.exit else ""
    return (
        f"{leg} takes the robot's body outside {full} when its centre passes "
        f"{_xy(breach.at)} ({body}){leaves}"
    )


def _xy(p: tuple[float, float]) -> str:
    return f"({p[0]:.2f}, {p[1]:.2f})"


def legs(pose: Pose2D, poses: list[Pose2D]) -> list[float]:
    points = [pose, *poses]
    return [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(points, points[1:], strict=False)]
