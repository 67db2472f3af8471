"""Going to things: what a target name means, sightings from the camera, search and approach.

Places and objects share one namespace: a name is a place (profile, taught, start, home) if
one has it, else an object the robot has seen (walk to a standoff point `search.standoff`
metres from it, facing it), else, with a map, an object not seen yet: look around, then visit
unexplored free space inside the geofence within the search budget (`search.max_seconds`,
`search.max_distance`, and what is left of the mission's own limits), then approach it. Every
leg the search walks passes the governor's path rules before it is walked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import geofence, typos
from ..config import SafetyConfig
from ..errors import PlanProblem, SkillError, SkillTimeout
from ..memory.service import AgentMemory
from ..robot.base import Robot
from ..state import Pose2D, normalize_angle
from ..world import (
    Belief,
    Coverage,
    KnownObject,
    PlanError,
    Viewpoint,
    object_key,
    standoff_point,
)
from . import motion, paths
from .context import PlanEnv, SkillContext

_QUARTER = math.pi / 2


@dataclass(frozen=True)
class Target:
    """What a name resolves to: a point (a place), a known object, or a search for `name`."""

    name: str
    point: tuple[float, float] | None = None
    known: KnownObject | None = None

    @property
    def search(self) -> bool:
        return self.point is None and self.known is None


def resolve(env: PlanEnv, name: str) -> Target:
    """A place first, then an object seen (by its name or its last words: "chair" for the
    one "yellow chair"; two that fit are a question), then the one place, object or
    recognisable kind whose name is a misspelling of `name` ("chargng dock"); with a map, a
    name the robot can recognise (`PlanEnv.vocabulary`) is an object to look for. Anything else
    is refused before moving, naming the word and what the robot knows."""
    try:
        return Target(name, point=env.resolve_place(name))
    except PlanProblem as exc:
        belief = env.belief
        known = find(belief, name)
        if known is not None:
            return Target(name, known=known)
        several = _ending_with(belief, name)
        if len(several) > 1:
            raise PlanProblem(
                f"{name!r} could be " + " or ".join(o.the_name for o in several) + ": say which"
            ) from exc
        kinds = sorted(env.vocabulary or ())
        # A kind it recognises, named as it is, is not a misspelling of another ("car", "cat").
        if env.vocabulary is None or not recognisable(env.vocabulary, name):
            near = _misspelt(name, [*env.places, *(o.name for o in _objects(belief)), *kinds])
            if near is not None:
                return resolve(env, near)
        if belief is None or not name.strip() or not recognisable(env.vocabulary, name):
            raise PlanProblem(unknown(env, name)) from exc
        return Target(name)


def recognisable(vocabulary: frozenset[str] | None, name: str) -> bool:
    """Whether the robot can recognise `name` to look for it: one of the kinds it knows, by
    its name or its last words ("chair" for "yellow chair"); any name when its vocabulary is
    not known in advance (None)."""
    if vocabulary is None:
        return True
    key = object_key(name)
    return bool(key) and any(
        object_key(v) == key or object_key(v).endswith(" " + key) for v in vocabulary
    )


def unknown(env: PlanEnv, name: str) -> str:
    """Why a name cannot be gone to: what the robot knows instead, and any name that shares a
    word with it ("charging station": did you mean the charging dock?)."""
    places = [*env.places, "start", "home"]
    seen = [o.name for o in _objects(env.belief)]
    kinds = sorted(env.vocabulary or ())
    words = set(object_key(name).split())
    alike = sorted({n for n in (*env.places, *seen, *kinds) if words & set(n.lower().split())})
    text = (
        f"{name!r} is not a place or an object I know"
        + (", nor a thing I can recognise to look for" if env.belief is not None else "")
        + f". Places: {', '.join(places)}. Objects seen: {', '.join(seen) or 'none yet'}."
    )
    if env.belief is not None and env.vocabulary is not None:
        text += f" I can look for: {', '.join(kinds) or 'nothing (no detector)'}."
    if alike:
        text += " Did you mean " + " or ".join(f"the {n}" for n in alike) + "?"
    return text + secondhand(env, name)


def secondhand(env: PlanEnv, name: str) -> str:
    """What other robots (or no known robot) remember by `name`, and that it is no goal here,
    as sentences to follow another (" The yellow chair was seen by robot 'sim', not by this
    robot: not a goal."); "" when nothing. Their memories are never goals (memory.records)."""
    key = object_key(name)
    notes = []
    for other in env.secondhand:
        theirs = object_key(other.name)
        if key and (theirs == key or theirs.endswith(" " + key) or key.endswith(" " + theirs)):
            notes.append(f" {other.note[0].upper()}{other.note[1:]}.")
    return "".join(dict.fromkeys(notes))


def find(belief: Belief | None, name: str) -> KnownObject | None:
    """The object seen that `name` names: exactly, by its last words, or misspelt."""
    if belief is None:
        return None
    known = belief.find(name)
    if known is None:
        near = _misspelt(name, [o.name for o in belief.objects])
        known = belief.find(near) if near is not None else None
    return known


def _ending_with(belief: Belief | None, name: str) -> list[KnownObject]:
    key = " ".join(name.strip().lower().split()).removeprefix("the ")
    return [o for o in _objects(belief) if o.name.endswith(" " + key)]


def _objects(belief: Belief | None) -> tuple[KnownObject, ...]:
    return belief.objects if belief is not None else ()


def _misspelt(name: str, names: list[str]) -> str | None:
    """The one name of `names` that `name` is a misspelling of, word by word (each word within
    the spelling reader's distance, first letters equal); None if none or several."""
    key = " ".join(name.strip().lower().split()).removeprefix("the ").split()
    found = set()
    for candidate in names:
        words = candidate.lower().split()
        if len(words) != len(key) or words == key:
            continue
        if all(
            a[0] == b[0] and typos.distance(a, b, typos.limit(b)) <= typos.limit(b)
            for a, b in zip(key, words, strict=True)
        ):
            found.add(candidate)
    return found.pop() if len(found) == 1 else None


def seen_list(belief: Belief | None) -> str:
    objects = belief.objects if belief is not None else ()
    return ", ".join(o.name for o in objects) or "none yet"


def standoff(env: PlanEnv, pose: Pose2D, obj: KnownObject) -> Pose2D:
    """The pose `search.standoff` metres from `obj`, facing it, reachable from `pose`."""
    assert env.belief is not None  # a known object comes from the belief
    try:
        return standoff_point(env.belief, (pose.x, pose.y), obj, env.config.search.standoff).pose
    except PlanError as exc:
        raise PlanProblem(f"cannot go to {obj.the_name}: {exc}") from exc


# -- sightings ------------------------------------------------------------------------------


def sight_in_view(ctx: SkillContext) -> list[KnownObject]:
    """What the robot's own camera reports in view now, remembered in the belief (and in
    memory, when it keeps sightings). A camera that reports no sightings adds nothing."""
    return record_view(ctx.robot, ctx.env.belief, ctx.memory)


def record_view(
    robot: Robot, belief: Belief | None, memory: AgentMemory | None = None
) -> list[KnownObject]:
    """`sight_in_view` for callers without a SkillContext (the agent, before planning).
    Nothing is placed while the robot's own position is not finite numbers."""
    if belief is None:
        return []
    frame = robot.get_camera_frame()
    if frame is None or not frame.sightings:
        return []
    pose = robot.get_state().pose
    if pose.unknown():  # odometry that lies: where the objects in view are is not known
        return []
    stamp = robot.now()
    seen = []
    for s in frame.sightings:
        a = pose.yaw + math.radians(s.bearing_deg)
        seen.append(
            belief.sight(
                s.name, pose.x + s.distance * math.cos(a), pose.y + s.distance * math.sin(a), stamp
            )
        )
    if memory is not None:
        for obj in seen:
            memory.sightings.remember(obj)
    return seen


def see_at_start(robot: Robot, belief: Belief | None, memory: AgentMemory | None = None) -> None:
    """Before a mission is planned: what memory holds of earlier sightings, then what is in
    view now, enter the belief."""
    if belief is None:
        return
    if memory is not None:
        for remembered in memory.sightings.all():
            belief.remember(remembered.known)
    record_view(robot, belief, memory)


# -- search ---------------------------------------------------------------------------------


def look_around(ctx: SkillContext, name: str, angular: float) -> KnownObject | None:
    """Turn a full circle in quarters, sighting at each; stop as soon as `name` is seen."""
    belief = ctx.env.belief
    assert belief is not None
    for quarter in range(4):
        if quarter:
            motion.rotate(ctx, _QUARTER, angular, relative=True)
        ctx.robot.look()  # a detector reports at its own rate: let it see this view
        sight_in_view(ctx)
        found = find(belief, name)
        if found is not None:
            return found
    return None


def _fits(ctx: SkillContext, deadline: float, seconds: float) -> bool:
    return ctx.robot.now() + seconds <= deadline


def search(ctx: SkillContext, name: str, linear: float, angular: float) -> KnownObject:
    """Look for `name` within the search budget; return it once seen. Raises SkillError that
    says where the robot looked when the budget or the reachable space runs out."""
    ctx.env.searched.add(name)
    belief = ctx.env.belief
    assert belief is not None
    if elsewhere := secondhand(ctx.env, name):  # looked for, never walked to
        ctx.notes.append(elsewhere.strip().rstrip("."))
    cfg, safety, m = ctx.config.search, ctx.config.safety, ctx.config.motion
    robot = ctx.robot
    start = robot.get_state()
    deadline = robot.now() + cfg.max_seconds
    budget = ctx.env.budget
    left_for_mission = safety.max_mission_distance - (budget.travelled(start) if budget else 0.0)
    max_walk = max(0.0, min(cfg.max_distance, left_for_mission))
    coverage = Coverage(belief, cfg.view_range)
    turn = 3 * motion.rotate_timeout(_QUARTER, angular, m.angular_accel)
    walked = 0.0
    why = "the search's time ran out (search.max_seconds)"
    saved_deadline, saved_late = ctx.deadline, ctx._late
    if deadline < ctx.deadline:  # the search's own time limit binds every control loop
        ctx.deadline, ctx._late = deadline, why
    try:
        while True:
            pose = robot.get_state().pose
            if not _fits(ctx, deadline, turn):
                break
            found = look_around(ctx, name, angular)
            coverage.look((pose.x, pose.y))
            if found is not None:
                ctx.notes.append(
                    f"found {found.the_name} at ({found.x:.2f}, {found.y:.2f}) "
                    f"after {len(coverage.looked_from)} look(s) and "
                    f"{walked:.1f} m of search"
                )
                return found
            pose = robot.get_state().pose
            view = _next_view(
                coverage,
                ctx,
                pose,
                max_walk - walked,
                deadline - robot.now() - turn,
                linear,
                angular,
            )
            if view is None:
                why = (
                    "no unexplored free space is left within reach inside the geofence "
                    "and the search budget"
                )
                break
            before = robot.get_state().distance_travelled
            try:
                motion.follow(ctx, list(view.path.waypoints[1:]), linear, angular)
            finally:
                walked += robot.get_state().distance_travelled - before
    except SkillTimeout:
        if ctx.deadline != deadline:
            raise  # the mission's own time limit: not the search's to explain
        robot.stop()
    finally:
        ctx.deadline, ctx._late = saved_deadline, saved_late
    places = ", ".join(f"({x:.1f}, {y:.1f})" for x, y in coverage.looked_from) or "nowhere"
    raise SkillError(
        f"did not find {the(name)}: looked around from {places}, walked {walked:.1f} m in "
        f"{robot.now() - start.stamp:.0f} s; {why} (budget {cfg.max_seconds:g} s, "
        f"{max_walk:g} m: search.max_seconds, search.max_distance). Objects seen: "
        f"{seen_list(belief)}{direction_only(robot, name)}"
    )


def direction_only(robot: Robot, name: str) -> str:
    """What the robot saw of `name` in a direction only (its latest such sighting), as a
    sentence to follow another (". The chair was seen only in a direction ..."); "" if none."""
    key = object_key(name)
    for b in reversed(robot.bearings()):
        seen = object_key(b.name)
        if seen == key or key.endswith(" " + seen) or seen.endswith(" " + key):
            where = f"{math.degrees(b.direction):.0f} degrees from ({b.x:.1f}, {b.y:.1f})"
            said = the(b.name)
            return (
                f". {said[0].upper()}{said[1:]} was seen only in a direction ({where}), at no "
                f"known distance ({b.why}): a direction is never a place to go"
            )
    return ""


def inside_fences(limits: SafetyConfig, p: tuple[float, float]) -> bool:
    """Whether a body at `p` keeps `geofence_margin` inside the circle and polygon fences."""
    fences: list[geofence.Fence] = [geofence.CircleFence(limits.geofence_radius)]
    if limits.geofence_polygon:
        fences.append(geofence.PolygonFence(limits.geofence_polygon))
    return all(f.clearance(p) >= limits.geofence_margin for f in fences)


def _next_view(
    coverage: Coverage,
    ctx: SkillContext,
    pose: Pose2D,
    max_walk: float,
    seconds: float,
    linear: float,
    angular: float,
) -> Viewpoint | None:
    """The next viewpoint whose path fits the time left and passes the governor's rules."""
    m = ctx.config.motion
    safety = ctx.config.safety
    tried: set[tuple[float, float]] = set()
    for _ in range(4):  # a viewpoint the governor refuses is skipped, then the next best
        view = coverage.next_viewpoint(
            (pose.x, pose.y), lambda p: p not in tried and inside_fences(safety, p), max_walk
        )
        if view is None:
            return None
        tried.add(view.point)
        corners = len(view.path.waypoints) - 1
        needs = motion.straight_timeout(
            view.path.length, linear, m.linear_accel
        ) + corners * motion.rotate_timeout(math.pi, angular, m.angular_accel)
        if needs > seconds:
            coverage.seen.update(coverage.visible_from(view.point))  # out of time's reach
            continue
        poses = _corner_poses(pose, list(view.path.waypoints[1:]))
        if paths.path_problems(ctx.config.safety, pose, poses, ctx.env, "the search path"):
            continue
        return view
    return None


def _corner_poses(pose: Pose2D, points: list[tuple[float, float]]) -> list[Pose2D]:
    poses: list[Pose2D] = []
    last = pose
    for x, y in points:
        last = Pose2D(x, y, math.atan2(y - last.y, x - last.x))
        poses.append(last)
    return poses


def the(name: str) -> str:
    """The name with "the" before it, as a sentence says it ("the chair" for "chair")."""
    key = " ".join(name.strip().split())
    return key if key.lower().startswith("the ") else f"the {key}"


def face(ctx: SkillContext, obj: KnownObject, angular: float) -> None:
    """Turn in place to face the object's centre."""
    st = ctx.robot.get_state()
    bearing = math.atan2(obj.y - st.y, obj.x - st.x)
    motion.rotate(ctx, normalize_angle(bearing - st.yaw), angular)
