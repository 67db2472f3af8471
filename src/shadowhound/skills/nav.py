"""Navigation skills: nav.move, nav.strafe, nav.rotate, nav.goto, nav.patrol, nav.stop.

Long because: the six skills share their argument readers, speed caps and path predictors, and
each skill's arguments, `predict`, `run` and `timeout` sit together; the motion loops
(motion.py), path rules (paths.py), Nav2 use (navigate.py) and objects (objects.py) are apart.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from pydantic import ConfigDict, Field, model_validator

from ..errors import PlanProblem, Relocalized, SkillError
from ..state import Pose2D, normalize_angle, not_finite, position_unknown
from ..units import format_number as _n
from ..world import NearGoal, PlanError, apply_scan, near_goal, plan_route
from . import motion, navigate, objects, paths
from .arguments import (
    Angle,
    Length,
    NoArgs,
    OptionalAngle,
    OptionalAngularSpeed,
    OptionalCount,
    OptionalLength,
    OptionalSpeed,
    SkillArgs,
)
from .context import PlanEnv, SkillContext
from .registry import Skill

# Schema ranges are sanity bounds on the form of a request; the configured safety limits
# (SafetyConfig) are checked on top of them before anything moves.
_MAX_DISTANCE = 1000.0
# Times a walk re-plans after something it did not know of stopped it (then it gives up).
MAX_REPLANS = 3


class MoveArgs(SkillArgs):
    distance: Length = Field(
        ge=-_MAX_DISTANCE, le=_MAX_DISTANCE, description="metres; + forward, - backward"
    )
    speed: OptionalSpeed = Field(None, gt=0, le=1.5, description="m/s")


class StrafeArgs(SkillArgs):
    distance: Length = Field(
        ge=-_MAX_DISTANCE, le=_MAX_DISTANCE, description="metres sideways; + left, - right"
    )
    speed: OptionalSpeed = Field(None, gt=0, le=1.5, description="m/s")


class RotateArgs(SkillArgs):
    degrees: Angle = Field(ge=-3600, le=3600, description="+ left (counter-clockwise), - right")
    speed: OptionalAngularSpeed = Field(None, gt=0, le=3.0, description="rad/s")


class GotoArgs(SkillArgs):
    # The targets `_target` accepts, in JSON Schema: plan schemas offer each as its own step.
    model_config = ConfigDict(
        json_schema_extra={"oneOf": [{"required": ["x", "y"]}, {"required": ["place"]}]}
    )

    x: OptionalLength = Field(None, ge=-_MAX_DISTANCE, le=_MAX_DISTANCE, description="metres, odom")
    y: OptionalLength = Field(None, ge=-_MAX_DISTANCE, le=_MAX_DISTANCE, description="metres, odom")
    place: str | None = Field(
        None,
        min_length=1,
        max_length=100,
        description="place or object (start, home)",
    )
    heading_degrees: OptionalAngle = Field(
        None, ge=-360, le=360, description="final heading, degrees"
    )
    speed: OptionalSpeed = Field(None, gt=0, le=1.5, description="m/s")

    @model_validator(mode="after")
    def _target(self) -> GotoArgs:
        has_xy = self.x is not None or self.y is not None
        if has_xy and self.place is not None:
            raise ValueError("give either x and y, or a place, not both")
        if has_xy and (self.x is None or self.y is None):
            raise ValueError("give both x and y (metres in the odom frame)")
        if not has_xy and self.place is None:
            raise ValueError("give a target: x and y in metres, or a place name")
        return self


class PatrolArgs(SkillArgs):
    laps: OptionalCount = Field(
        1,
        ge=1,
        le=20,
        description="times round the route; null: until stopped (as the mission's limits allow)",
    )


def _linear(ctx_or_env: SkillContext | PlanEnv, speed: float | None) -> float:
    return speed or ctx_or_env.config.motion.default_linear_speed


def _angular(ctx_or_env: SkillContext | PlanEnv, speed: float | None) -> float:
    return speed or ctx_or_env.config.motion.default_angular_speed


def _offset(pose: Pose2D, forward: float, left: float) -> Pose2D:
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return Pose2D(pose.x + forward * c - left * s, pose.y + forward * s + left * c, pose.yaw)


# -- nav.move / nav.strafe -------------------------------------------------------------------


def _run_move(ctx: SkillContext, a: MoveArgs) -> str:
    ctx.ensure_standing()
    covered = motion.drive_local(ctx, a.distance, 0.0, _linear(ctx, a.speed), relative=True)
    objects.sight_in_view(ctx)
    return f"moved {covered:.2f} m {'forward' if a.distance >= 0 else 'backward'}"


def _run_strafe(ctx: SkillContext, a: StrafeArgs) -> str:
    ctx.ensure_standing()
    covered = motion.drive_local(ctx, 0.0, a.distance, _linear(ctx, a.speed), relative=True)
    objects.sight_in_view(ctx)
    return f"stepped {covered:.2f} m to the {'left' if a.distance >= 0 else 'right'}"


def _straight_timeout(a: MoveArgs | StrafeArgs, env: PlanEnv) -> float:
    accel = env.config.motion.linear_accel
    speed = _linear(env, a.speed)
    return motion.straight_timeout(a.distance, speed, accel) + motion.CORRECTIONS_ALLOWANCE


# -- nav.rotate ------------------------------------------------------------------------------


def _run_rotate(ctx: SkillContext, a: RotateArgs) -> str:
    ctx.ensure_standing()
    turned = motion.rotate(ctx, math.radians(a.degrees), _angular(ctx, a.speed), relative=True)
    objects.sight_in_view(ctx)
    side = "left (counter-clockwise)" if a.degrees >= 0 else "right (clockwise)"
    return f"turned {abs(math.degrees(turned)):.1f} degrees {side}"


def _rotate_timeout(a: RotateArgs, env: PlanEnv) -> float:
    return (
        motion.rotate_timeout(
            math.radians(a.degrees), _angular(env, a.speed), env.config.motion.angular_accel
        )
        + motion.CORRECTIONS_ALLOWANCE
    )


# -- nav.goto --------------------------------------------------------------------------------


def _goto_target(a: GotoArgs, env: PlanEnv) -> tuple[float, float]:
    if a.place is not None:
        return env.resolve_place(a.place)
    assert a.x is not None and a.y is not None  # guaranteed by GotoArgs._target
    return (a.x, a.y)


def _goal(env: PlanEnv, pose: Pose2D, a: GotoArgs) -> tuple[tuple[float, float], NearGoal | None]:
    """Where a go-to to a point or a place stands: the goal, or, when it lies inside
    something's clearance on the map, the nearest reachable point that keeps the body clear
    (as Nav2's planner tolerance does), with what was in the way."""
    goal = _goto_target(a, env)
    if env.belief is None:
        return goal, None
    try:
        near = near_goal(env.belief, (pose.x, pose.y), goal)
    except PlanError as exc:
        raise PlanProblem(f"cannot go to ({goal[0]:.2f}, {goal[1]:.2f}): {exc}") from exc
    return (goal, None) if near is None else (near.point, near)


def route(env: PlanEnv, start: Pose2D, goal: tuple[float, float]) -> list[tuple[float, float]]:
    """The points a walk from `start` to `goal` passes, the goal last: with a map, the planned
    collision-free path; without one, the goal alone (a straight line, as before maps).
    Raises PlanProblem when there is none, also when the start or the goal is not finite."""
    if why := position_unknown(start):
        raise PlanProblem(f"{why}: cannot plan a walk from there")
    if bad := not_finite(x=goal[0], y=goal[1]):
        raise PlanProblem(
            f"the goal is not a point the robot can walk to: it is not finite ({bad})"
        )
    if env.belief is None:
        return [goal]
    try:
        path = plan_route(env.belief, (start.x, start.y), goal)
    except PlanError as exc:
        raise PlanProblem(f"no safe path to ({goal[0]:.2f}, {goal[1]:.2f}): {exc}") from exc
    points = list(path.waypoints[1:]) or [goal]
    if math.dist(points[-1], goal) < 1e-6:  # the exact goal, not its round trip through cells
        points[-1] = goal
    return points


def walk(ctx: SkillContext, goal: tuple[float, float], linear: float, angular: float) -> float:
    """Walk a planned path to `goal`. When something the map did not show stops the robot
    (the state's `blocked_by`), update the map from a scan and plan again; when localization
    corrects the robot's map pose on the way (SLAM), plan again from the corrected pose; at most
    MAX_REPLANS times in all. Returns metres covered."""
    walked = 0.0
    belief = ctx.env.belief
    for attempt in range(MAX_REPLANS + 1):
        pose = ctx.robot.get_state().pose
        try:
            points = route(ctx.env, pose, goal)
        except PlanProblem as exc:
            raise SkillError(str(exc)) from exc
        if attempt:  # a new path the plan check never saw: the governor's rules check it now
            _check_new_path(ctx, pose, points)
        before = ctx.robot.get_state().distance_travelled
        try:
            return walked + motion.follow(ctx, points, linear, angular, done=walked)
        except Relocalized as exc:
            walked += ctx.robot.get_state().distance_travelled - before
            if attempt == MAX_REPLANS:
                raise
            ctx.notes.append(f"{exc}; planned again from the corrected position")
            continue
        except SkillError as exc:
            walked += ctx.robot.get_state().distance_travelled - before
            blocked = ctx.robot.get_state().blocked_by
            if belief is None or not blocked or attempt == MAX_REPLANS:
                raise
            scan = ctx.robot.get_scan()
            if scan is None:
                raise
            apply_scan(belief.grid, scan)
            belief.changed()
            ctx.notes.append(f"{exc}; re-planned from a fresh scan")
    raise AssertionError("unreachable")  # the loop returns or raises


def _check_new_path(
    ctx: SkillContext,
    pose: Pose2D,
    points: list[tuple[float, float]],
    lead: str = "re-planned, but the new path is refused",
) -> None:
    poses = _predict_walk_points(pose, points, ctx.env)
    problems = paths.path_problems(ctx.config.safety, pose, poses, ctx.env, "the new path")
    if problems:
        raise SkillError(f"{lead}: " + "; ".join(problems))


def _run_goto(ctx: SkillContext, a: GotoArgs) -> str:
    ctx.ensure_standing()
    linear, angular = _linear(ctx, a.speed), _angular(ctx, None)
    target = objects.resolve(ctx.env, a.place) if a.place is not None else None
    if target is not None and target.point is None:
        return _approach(ctx, a, target, linear, angular)
    goal = _goto_target(a, ctx.env)
    point, near = _goal(ctx.env, ctx.robot.get_state().pose, a)
    _walk_to(
        ctx,
        point,
        lambda: _predict_goto(ctx.robot.get_state().pose, a, ctx.env)[-1].yaw,
        linear,
        angular,
    )
    names = {None: "the point", "start": "where the mission started", "home": "home"}
    where = names.get(a.place, f"the {a.place}")
    if near is not None:
        if a.heading_degrees is None:  # face what it could not stand on
            st = ctx.robot.get_state()
            motion.rotate(
                ctx, normalize_angle(math.atan2(goal[1] - st.y, goal[0] - st.x) - st.yaw), angular
            )
        ctx.notes.append(
            f"{where} ({goal[0]:.2f}, {goal[1]:.2f}) lies within {near.what}'s clearance: "
            f"went to the nearest point that keeps the body clear, {near.moved:.2f} m from it"
            + (", facing it" if a.heading_degrees is None else "")
        )
    _final_heading(ctx, a)
    objects.sight_in_view(ctx)
    st = ctx.robot.get_state()
    return f"reached {where} at x={st.x:.2f} m, y={st.y:.2f} m"


def _walk_to(
    ctx: SkillContext,
    goal: tuple[float, float],
    yaw: Callable[[], float],
    linear: float,
    angular: float,
) -> None:
    """Walk to `goal`: through the robot's Nav2 when `navigation` chooses it (it plans and
    drives, we watch, cancel and finish facing `yaw()`), else the project's own planned path."""
    navigator = navigate.choose(ctx)
    if navigator is None:
        walk(ctx, goal, linear, angular)
        return
    navigate.navigate(ctx, navigator, goal, yaw(), linear, angular)
    ctx.notes.append(f"through {navigator.name}")


def _final_heading(ctx: SkillContext, a: GotoArgs) -> None:
    if a.heading_degrees is not None:
        yaw = ctx.robot.get_state().yaw
        turn = normalize_angle(math.radians(a.heading_degrees) - yaw)
        motion.rotate(ctx, turn, _angular(ctx, None))


def _approach(
    ctx: SkillContext, a: GotoArgs, target: objects.Target, linear: float, angular: float
) -> str:
    """Walk to an object's standoff and face it; search for it first when not seen yet."""
    found = target.known
    if found is None:
        found = objects.search(ctx, target.name, linear, angular)
    pose = ctx.robot.get_state().pose
    try:
        spot = objects.standoff(ctx.env, pose, found)
    except PlanProblem as exc:
        raise SkillError(str(exc)) from exc
    # After a search (in this step or an earlier one of the mission) the plan check saw no
    # path: the governor checks the approach now, as it does every re-planned path.
    _check_new_path(
        ctx,
        pose,
        route(ctx.env, pose, (spot.x, spot.y)),
        f"the path to {found.the_name} is refused",
    )
    _walk_to(
        ctx,
        (spot.x, spot.y),
        lambda: math.atan2(found.y - spot.y, found.x - spot.x),
        linear,
        angular,
    )
    if a.heading_degrees is None:
        objects.face(ctx, found, angular)
    _final_heading(ctx, a)
    objects.sight_in_view(ctx)
    now = objects.find(ctx.env.belief, found.name)
    if now is not None and now.remembered:  # it was not seen again on the way or on arrival
        ctx.notes.append(
            f"{found.the_name} was remembered from an earlier mission and is not in view now"
        )
    st = ctx.robot.get_state()
    gap = math.hypot(found.x - st.x, found.y - st.y) - found.radius
    return (
        f"reached {found.the_name} (seen at {found.x:.2f}, {found.y:.2f}): standing "
        f"{gap:.2f} m from it at x={st.x:.2f} m, y={st.y:.2f} m, facing it"
        if a.heading_degrees is None
        else f"reached {found.the_name}: standing {gap:.2f} m from it at x={st.x:.2f} m, "
        f"y={st.y:.2f} m"
    )


def _arrive(pose: Pose2D, x: float, y: float, env: PlanEnv) -> Pose2D:
    """Where motion.go_to leaves the robot: facing along the leg it walked (if it walked)."""
    if pose.distance_to(x, y) < env.config.motion.position_tolerance:
        return Pose2D(x, y, pose.yaw)
    return Pose2D(x, y, math.atan2(y - pose.y, x - pose.x))


def _predict_walk(pose: Pose2D, goal: tuple[float, float], env: PlanEnv) -> list[Pose2D]:
    """The poses at the corners of the walk's path (every leg checked by the governor)."""
    return _predict_walk_points(pose, route(env, pose, goal), env)


def _predict_walk_points(
    pose: Pose2D, points: list[tuple[float, float]], env: PlanEnv
) -> list[Pose2D]:
    poses: list[Pose2D] = []
    for x, y in points:
        poses.append(_arrive(poses[-1] if poses else pose, x, y, env))
    return poses


def _predict_goto(pose: Pose2D, a: GotoArgs, env: PlanEnv) -> list[Pose2D]:
    target = objects.resolve(env, a.place) if a.place is not None else None
    if target is not None and (target.search or target.name in env.searched):
        return []  # where it will be found is not known: the search checks each leg it walks
    if target is not None and target.known is not None:
        spot = objects.standoff(env, pose, target.known)
        poses = _predict_walk(pose, (spot.x, spot.y), env)
        end = poses[-1]
        poses[-1] = Pose2D(end.x, end.y, spot.yaw)
    else:
        point, near = _goal(env, pose, a)
        poses = _predict_walk(pose, point, env)
        if near is not None:  # it ends facing the goal it could not stand on
            goal, end = _goto_target(a, env), poses[-1]
            poses[-1] = Pose2D(end.x, end.y, math.atan2(goal[1] - end.y, goal[0] - end.x))
    if a.heading_degrees is not None:
        end = poses[-1]
        poses[-1] = Pose2D(end.x, end.y, normalize_angle(math.radians(a.heading_degrees)))
    return poses


def _goto_timeout(a: GotoArgs, env: PlanEnv) -> float:
    # The distance is not known before the pose is; bound it by the geofence diameter (with a
    # map, twice that for detours, and a turn at each of a few corners).
    detours = 1 if env.belief is None else 2
    reach = 2 * env.config.safety.geofence_radius * detours
    m = env.config.motion
    # A name may be an object to look for first: the search has its own time on top.
    searching = env.config.search.max_seconds if a.place and env.belief is not None else 0.0
    return (
        motion.straight_timeout(reach, _linear(env, a.speed), m.linear_accel)
        + detours * 2 * (motion.rotate_timeout(2 * math.pi, _angular(env, None), m.angular_accel))
        + searching
    )


# -- nav.patrol ------------------------------------------------------------------------------


def _patrol_points(pose: Pose2D, env: PlanEnv) -> list[tuple[float, float]]:
    return [*env.config.patrol_route, (pose.x, pose.y)]


def _run_patrol(ctx: SkillContext, a: PatrolArgs) -> str:
    ctx.ensure_standing()
    st = ctx.robot.get_state()
    points = _patrol_points(st.pose, ctx.env)
    count = _laps(st.pose, a, ctx.env)
    walked = 0.0
    for _ in range(count):
        for point in points:
            walked += walk(ctx, point, _linear(ctx, None), _angular(ctx, None))
            objects.sight_in_view(ctx)
    laps = "lap" if count == 1 else "laps"
    done = f"patrolled {count} {laps} of {len(points)} waypoints ({walked:.1f} m) and returned"
    if a.laps is None:
        done += ": the mission's distance and time limits allow no more"
    return done


def _laps(pose: Pose2D, a: PatrolArgs, env: PlanEnv) -> int:
    """The laps a patrol walks: as asked, or (laps None: until stopped) as many whole laps as
    the mission's distance and time left allow at the default speed (at least 1, at most 20:
    the plan check then refuses what does not fit)."""
    if a.laps is not None:
        return a.laps
    points = [(pose.x, pose.y), *_patrol_points(pose, env)]
    lap = sum(math.dist(p, q) for p, q in zip(points, points[1:], strict=False))
    if lap <= 0:
        return 1
    lim, budget = env.config.safety, env.budget
    walked = budget.commanded if budget is not None else 0.0
    spent = budget.elapsed() if budget is not None else 0.0
    by_distance = (lim.max_mission_distance - walked) / lap
    seconds = lap / env.config.motion.default_linear_speed * 1.5 + 3.0 * len(points)
    by_time = (lim.max_mission_duration - spent) / seconds
    return max(1, min(20, int(min(by_distance, by_time))))


def _predict_patrol(pose: Pose2D, a: PatrolArgs, env: PlanEnv) -> list[Pose2D]:
    poses: list[Pose2D] = []
    for _ in range(_laps(pose, a, env)):
        for point in _patrol_points(pose, env):
            poses += _predict_walk(poses[-1] if poses else pose, point, env)
    return poses


def _patrol_timeout(a: PatrolArgs, env: PlanEnv) -> float:
    legs = len(env.config.patrol_route) + 1
    laps = _laps(env.mission_start or Pose2D(), a, env)
    return laps * legs * _goto_timeout(GotoArgs(x=0.0, y=0.0, place=None), env)


def _forecast_goto(a: GotoArgs, env: PlanEnv) -> str:
    """A go-to that must look for its object first: what the search may use."""
    try:
        target = objects.resolve(env, a.place) if a.place is not None else None
    except PlanProblem:
        return ""  # refused: the check says why
    if target is None or not target.search:
        return ""
    cfg = env.config.search
    return (
        f"would look for {objects.the(target.name)} (not seen yet) for up to "
        f"{cfg.max_seconds:g} s and {cfg.max_distance:g} m (search.max_seconds, "
        "search.max_distance), then go to it: where it ends is not known before it runs"
    )


def _forecast_patrol(a: PatrolArgs, env: PlanEnv) -> str:
    """A patrol until stopped: how many laps the mission's limits allow at most."""
    if a.laps is not None:
        return ""
    laps = _laps(env.mission_start, a, env)
    return (
        f"would patrol lap after lap until stopped, at most {laps} lap{'s' if laps != 1 else ''}"
        " (the mission's distance and time limits: safety.max_mission_distance, "
        "max_mission_duration)"
    )


def _say_patrol(a: PatrolArgs) -> str:
    if a.laps is None:
        return "keep patrolling"
    return f"patrol {a.laps} lap{'s' if a.laps != 1 else ''}"


def _say_goto(a: GotoArgs) -> str:
    if a.place is not None:
        return {"start": "return to the start", "home": "go home"}.get(a.place, f"go to {a.place}")
    if a.x is None or a.y is None:  # only as proposed, unchecked (GotoArgs._target refuses it)
        return "go to a point"
    return f"go to ({_n(a.x)}, {_n(a.y)})"


# -- nav.stop --------------------------------------------------------------------------------


def _run_stop(ctx: SkillContext, _a: NoArgs) -> str:
    ctx.robot.stop()
    motion.settle(ctx)
    return "stopped"


SKILLS = (
    Skill(
        "nav.move",
        "Walk straight forward (+) or backward (-), keeping the heading.",
        MoveArgs,
        _run_move,
        timeout=_straight_timeout,
        moves=True,
        drives="forward",
        predict=lambda p, a, env: [_offset(p, a.distance, 0.0)],
        phrase=lambda a: (
            f"move {'forward' if a.distance >= 0 else 'backward'} {_n(abs(a.distance))} m"
        ),
    ),
    Skill(
        "nav.strafe",
        "Step sideways left (+) or right (-) without turning.",
        StrafeArgs,
        _run_strafe,
        timeout=_straight_timeout,
        moves=True,
        drives="sideways",
        predict=lambda p, a, env: [_offset(p, 0.0, a.distance)],
        phrase=lambda a: f"step {'left' if a.distance >= 0 else 'right'} {_n(abs(a.distance))} m",
    ),
    Skill(
        "nav.rotate",
        "Turn in place: + left (counter-clockwise), - right.",
        RotateArgs,
        _run_rotate,
        timeout=_rotate_timeout,
        moves=True,
        drives="turn",
        predict=lambda p, a, env: [
            Pose2D(p.x, p.y, normalize_angle(p.yaw + math.radians(a.degrees)))
        ],
        phrase=lambda a: (
            f"turn {'left' if a.degrees >= 0 else 'right'} {_n(abs(a.degrees))} degrees"
        ),
    ),
    Skill(
        "nav.goto",
        "Walk around obstacles to a point (x, y metres), a place or an object (stops 0.6 m "
        "away facing it; looked for if not seen).",
        GotoArgs,
        _run_goto,
        timeout=_goto_timeout,
        moves=True,
        predict=_predict_goto,
        phrase=_say_goto,
        forecast=_forecast_goto,
    ),
    Skill(
        "nav.patrol",
        "Walk the configured patrol route laps times (null: until stopped) and return to the "
        "start.",
        PatrolArgs,
        _run_patrol,
        timeout=_patrol_timeout,
        moves=True,
        predict=_predict_patrol,
        forecast=_forecast_patrol,
        phrase=_say_patrol,
    ),
    Skill(
        "nav.stop",
        "Stop moving and stand still.",
        NoArgs,
        _run_stop,
        timeout=5.0,
        low_battery=True,
        phrase=lambda a: "stop",
    ),
)
