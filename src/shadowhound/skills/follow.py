"""nav.follow: keep a person or a thing in view at a set distance while it moves.

The robot turns to keep the target centred and walks to hold the distance (people: never
nearer than 1.0 m; it backs off when one comes closer), reading the target from its camera
(`Robot.in_view`) every control tick. It ends, as done, when the target has been out of view for
`LOST_AFTER` seconds, when its own `seconds` are up, or before the mission's time limit; a stop
from any interface ends it as any step. Refused before moving when the robot cannot tell what
is in view, or does not see the target at the start (there is nothing to follow). Where it goes
is not known before it runs: every velocity passes the speed and acceleration caps, and every
tick the geofence and the mission's distance (`SkillContext.check`); it walks only as fast as
still lets it brake, `STOP_SHORT` before, whatever is in the way along where it goes: the
geofence, the mission's distance and anything on the map, by a mission leg's rule
(`SkillContext.room_on_path`). A person is not on the map: it keeps its distance from them. Like
every step that moves the robot, it ends at rest (the mission runner settles it).
"""

from __future__ import annotations

import math

from pydantic import Field

from ..errors import SkillError
from ..state import RobotState, Sighting
from ..world.objects import object_key
from .arguments import Length, OptionalDuration, SkillArgs
from .bounds import STOP_SHORT, brake_speed
from .context import PlanEnv, SkillContext
from .registry import Skill
from .watches import names

PERSON_NEAREST = 1.0  # metres (centre to centre) a followed person is never approached closer
_TURN_GAIN = 1.5  # rad/s per radian off centre
_WALK_GAIN = 0.8  # m/s per metre off the set distance
_BACK_OFF = 0.2  # m/s at most when backing away from someone too close
_PEOPLE = {"person", "people", "someone", "somebody", "me", "human", "man", "woman"}


LOST_AFTER = 3.0  # seconds out of view: the follow is over


class FollowArgs(SkillArgs):
    target: str = Field("person", min_length=1, max_length=60)
    distance: Length = Field(1.5, ge=0.3, le=5.0, description="metres")
    seconds: OptionalDuration = Field(None, gt=0, le=3600)


def _is_person(name: str) -> bool:
    return object_key(name) in _PEOPLE


def _spot(seen: tuple[Sighting, ...], key: str) -> Sighting | None:
    return next((s for s in seen if names(key, s.name)), None)


def _run_follow(ctx: SkillContext, a: FollowArgs) -> str:
    robot = ctx.robot
    key = "person" if _is_person(a.target) else object_key(a.target)
    view = robot.in_view()
    if view is None:
        raise SkillError(f"{robot.description} cannot tell what is in view: nothing to follow")
    if _spot(view, key) is None:
        raise SkillError(f"I do not see {_the(key)} to follow; nothing moved")
    keep = max(a.distance, PERSON_NEAREST + 0.3) if key == "person" else a.distance
    nearest = PERSON_NEAREST if key == "person" else max(0.3, keep - 0.5)
    ctx.ensure_standing()
    s = ctx.config.safety
    top = min(s.max_linear_speed, 2 * ctx.config.motion.default_linear_speed)
    turn = min(s.max_angular_speed, 1.5)
    start = robot.now()
    # Before the step's (the mission's) time runs out, with the time to come to rest after.
    end = ctx.deadline - 1.0 - top / s.max_linear_accel
    if a.seconds is not None:
        end = min(end, start + a.seconds)
    last_seen, bearing = start, 0.0
    state = robot.get_state()
    walked, before = 0.0, state.pose
    why = ""
    held: list[str] = []  # what it stopped short of, in the order met
    while True:
        now = robot.now()
        if now >= end:
            why = "its time is up" if a.seconds is not None else "the mission's time limit"
            break
        target = _spot(robot.in_view() or (), key)
        if target is not None:
            last_seen, bearing = now, math.radians(target.bearing_deg)
            off = target.distance - keep
            vx = max(-_BACK_OFF, min(top, _WALK_GAIN * off)) * max(0.0, math.cos(bearing))
            if target.distance < nearest + 0.1 or not math.isfinite(target.distance):
                vx = min(vx, 0.0)  # never on toward it (or toward one at no known distance)
            vx, limit = _within_room(ctx, vx, state)
            if limit and limit not in held:
                held.append(limit)
            ctx.drive(vx, 0.0, max(-turn, min(turn, _TURN_GAIN * bearing)))
        elif now - last_seen > LOST_AFTER:
            why = f"lost sight of {_the(key)} for {LOST_AFTER:g} s"
            break
        else:  # out of view a moment: stand, turned toward where it went
            ctx.drive(0.0, 0.0, max(-turn / 2, min(turn / 2, _TURN_GAIN * bearing)))
        ctx.tick()
        state = robot.get_state()
        walked += math.hypot(state.x - before.x, state.y - before.y)
        before = state.pose
    robot.stop()
    said = f"followed {_the(key)} for {robot.now() - start:.0f} s ({walked:.1f} m) until {why}"
    if held:
        said += f"; held back: {'; '.join(held[:3])}"
    return said


def _within_room(ctx: SkillContext, vx: float, state: RobotState) -> tuple[float, str]:
    """`vx` (forward +, back -) cut so the robot can still brake at safety.max_linear_accel,
    `STOP_SHORT` before whatever is in the way where it goes (`SkillContext.room_on_path`), and
    why it was cut ("" when it was not)."""
    speed = abs(vx)
    if speed < 1e-9:
        return vx, ""
    accel = ctx.config.safety.max_linear_accel
    heading = state.yaw + (0.0 if vx > 0 else math.pi)
    reach = speed * ctx.period + speed * speed / (2 * accel) + 0.5
    room, why = ctx.room_on_path(heading, reach, state)
    allowed = brake_speed(room - STOP_SHORT, accel, ctx.period)
    if allowed >= speed:
        return vx, ""
    return math.copysign(allowed, vx), why


def _the(name: str) -> str:
    return "you" if name == "me" else f"the {name}"


def _forecast(a: FollowArgs, env: PlanEnv) -> str:
    limit = env.config.safety
    return (
        f"would follow the {a.target} at {a.distance:g} m: where it goes is not known before it "
        f"runs; the geofence and the mission's {limit.max_mission_distance:g} m and "
        f"{limit.max_mission_duration:g} s bound it"
    )


def _timeout(a: FollowArgs, env: PlanEnv) -> float:
    limit = env.config.safety.max_mission_duration
    return min(limit, (a.seconds or limit) + 5.0)


SKILLS = (
    Skill(
        "nav.follow",
        "Follow a person or thing in view at a distance.",
        FollowArgs,
        _run_follow,
        timeout=_timeout,
        moves=True,  # no predicted path: not known before it runs, bounded as it goes
        forecast=_forecast,
        phrase=lambda a: f"follow the {a.target}",
    ),
)

__all__ = ["PERSON_NEAREST", "SKILLS", "FollowArgs"]
