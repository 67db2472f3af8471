"""nav.face: turn in place to face a thing, a place or a point ("face the blue box", "turn
towards the kitchen", "look at the person").

The bearing comes from what the robot knows: a place's position, an object it has seen. A
thing it can recognise but has not seen yet is looked for by turning in place (a look-around
in quarter turns, nothing more); a name it neither knows nor can recognise is refused before
anything moves, as nav.goto refuses it.
"""

from __future__ import annotations

import math

from pydantic import ConfigDict, Field, model_validator

from ..errors import PlanProblem, SkillError
from ..state import Pose2D, normalize_angle
from ..units import format_number as _n
from . import motion, objects
from .arguments import OptionalLength, SkillArgs
from .context import PlanEnv, SkillContext
from .registry import Skill


class FaceArgs(SkillArgs):
    # The targets `_target` accepts, in JSON Schema: plan schemas offer each as its own step.
    model_config = ConfigDict(
        json_schema_extra={"oneOf": [{"required": ["x", "y"]}, {"required": ["place"]}]}
    )

    # No bounds beyond finite numbers: turning toward a point, however far, moves nothing.
    x: OptionalLength = None  # metres, odom
    y: OptionalLength = None
    place: str | None = Field(None, min_length=1, max_length=100, description="place or object")

    @model_validator(mode="after")
    def _target(self) -> FaceArgs:
        has_xy = self.x is not None or self.y is not None
        if has_xy and self.place is not None:
            raise ValueError("give either x and y, or a place or object, not both")
        if has_xy and (self.x is None or self.y is None):
            raise ValueError("give both x and y (metres in the odom frame)")
        if not has_xy and self.place is None:
            raise ValueError("give what to face: x and y in metres, or a place or object name")
        return self


def _target(a: FaceArgs, env: PlanEnv) -> objects.Target:
    """What to face: a point, a place, an object seen, or (with a map) one to look for."""
    if a.place is None:
        assert a.x is not None and a.y is not None  # FaceArgs._target
        return objects.Target("the point", point=(a.x, a.y))
    return objects.resolve(env, a.place)


def _point(target: objects.Target) -> tuple[float, float]:
    if target.point is not None:
        return target.point
    assert target.known is not None  # not a search
    return (target.known.x, target.known.y)


def _bearing(pose: Pose2D, point: tuple[float, float]) -> float | None:
    """The heading from `pose` to `point`; None when the robot stands on it."""
    if math.hypot(point[0] - pose.x, point[1] - pose.y) < 1e-3:
        return None
    return math.atan2(point[1] - pose.y, point[0] - pose.x)


def _predict(pose: Pose2D, a: FaceArgs, env: PlanEnv) -> list[Pose2D]:
    target = _target(a, env)
    if target.search:  # found by turning in place: the heading is not known before
        return [pose]
    bearing = _bearing(pose, _point(target))
    return [Pose2D(pose.x, pose.y, pose.yaw if bearing is None else normalize_angle(bearing))]


def _run(ctx: SkillContext, a: FaceArgs) -> str:
    ctx.ensure_standing()
    angular = ctx.config.motion.default_angular_speed
    target = _target(a, ctx.env)
    name = (
        target.known.the_name
        if target.known is not None
        else "the point"
        if a.place is None
        else objects.the(a.place)
    )
    if target.search:  # recognisable, not seen yet: look around in place for it
        found = objects.look_around(ctx, target.name, angular)
        if found is None:
            raise SkillError(
                f"did not see {objects.the(target.name)} from here (turned a full circle); "
                f"objects seen: {objects.seen_list(ctx.env.belief)}"
            )
        target, name = objects.Target(found.name, known=found), found.the_name
    point = _point(target)
    st = ctx.robot.get_state()
    bearing = _bearing(st.pose, point)
    if bearing is None:
        return f"already at {name}: nothing to face"
    motion.rotate(ctx, normalize_angle(bearing - st.yaw), angular)
    objects.sight_in_view(ctx)
    yaw = ctx.robot.get_state().yaw
    where = f"({point[0]:.2f}, {point[1]:.2f})"
    return f"facing {name} {where}, heading {math.degrees(yaw):.0f} degrees"


def _timeout(_a: FaceArgs, env: PlanEnv) -> float:
    """A full look-around in quarter turns (for a thing not seen yet), then the turn to it."""
    m = env.config.motion
    return 5 * motion.rotate_timeout(math.pi / 2, m.default_angular_speed, m.angular_accel)


def _say(a: FaceArgs) -> str:
    if a.place is not None:
        return f"face {a.place}"
    if a.x is None or a.y is None:
        return "face a point"
    return f"face ({_n(a.x)}, {_n(a.y)})"


def _forecast(a: FaceArgs, env: PlanEnv) -> str:
    try:
        target = _target(a, env)
    except PlanProblem:
        return ""
    if not target.search:
        return ""
    return (
        f"would look around in place for {objects.the(target.name)} (not seen yet), then "
        "face it: the heading is not known before it runs"
    )


SKILLS = (
    Skill(
        "nav.face",
        "Turn in place to face a point (x, y), a place or an object.",
        FaceArgs,
        _run,
        timeout=_timeout,
        moves=True,
        predict=_predict,
        phrase=_say,
        forecast=_forecast,
    ),
)
