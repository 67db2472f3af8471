"""Closed-loop motion on the measured pose: straight lines, rotations, go-to-point.

Every loop commands velocity, lets one control period pass, then measures the pose again;
distance and angle are measured, never assumed from time. Velocity follows a ramp profile
(v = sqrt(2 a d) near the goal) and a final proportional approach, so the robot stops on the
target without overshoot. Arrival is judged again on the pose at rest (after `settle`), and a
short approach corrects what late odometry left; a loop fails if the robot makes no progress
for `stall_timeout`.

Whatever odometry says, a loop also brakes within the bounds of bounds.py: the travel (turn)
its leg may command in all, the room before the body would reach a geofence (from the measured
and the commanded pose) and the mission's distance left. A loop that has used them up while
odometry still shows the goal ahead stops and fails, naming the bound; only when the bound was
its own commands' and odometry shows it within the step's outcome tolerance does it end there,
saying so (a robot slow to start, a command late on the way: the commands ran ahead of it).
A leg or turn done is checked against its commands once more at rest (agreement.py):
odometry further along than the commands could take the robot is a lie, and fails.

On a loaded machine a command may be held up on its way, as long as the stalls seen
(`SkillContext.stall`): the loops brake that much sooner, and the commands' bound and the check
at rest allow for the honest difference (bounds.CommandLedger.leeway); a loop that makes no
progress within the step's outcome tolerance ends there, saying so.

Long because: the straight leg and the turn are one closed loop each, with the same approaches,
corrections and bounds; split, each half would need the other's helpers.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from ..errors import Relocalized, SkillError
from ..state import Pose2D, RobotState, carried, normalize_angle
from .agreement import (
    LATE,
    SLOW,
    absorbed_yaw,
    allowing,
    deg,
    disagree,
    ended_short,
    leg_agrees,
    turn_agrees,
)
from .bounds import leg_margin, leg_room, turn_margin, turn_room
from .context import SkillContext

_SETTLE_SPEED = 0.01
_SETTLE_SECONDS = 3.0  # longest wait for rest after a stop, besides the robot's pose lag
_CORRECTIONS = 3  # approaches after the first when the pose at rest is off the goal
# A correction moves slowly enough that odometry half a second later than the robot believes
# costs at most the tolerance (late odometry is what leaves the first approach off the goal).
_CORRECTION_SECONDS = 0.5


# Robot seconds a move or turn step allows its corrections after the first approach (each a
# slow approach of a few tolerances and the wait for the robot to show it at rest): on a loaded
# machine a late robot (a Go2 over DDS) may need all of them. Not part of the estimates above,
# which searches plan with.
CORRECTIONS_ALLOWANCE = _CORRECTIONS * 1.5


def straight_timeout(distance: float, speed: float, accel: float) -> float:
    return abs(distance) / speed + 2 * speed / accel + 5.0


def rotate_timeout(angle: float, speed: float, accel: float) -> float:
    return abs(angle) / speed + 2 * speed / accel + 5.0


def _profile(error: float, v_max: float, accel: float, period: float) -> float:
    """Speed toward a goal `error` away, never faster than `v_max`.

    The command is held for one control period and then the robot must still be able to brake
    at `accel`: v * period + v^2 / (2 accel) <= |error|. Solving for v gives the ramp below,
    which also shrinks smoothly to zero at the goal (no overshoot, no chatter).
    """
    magnitude = accel * (math.sqrt(period * period + 2 * abs(error) / accel) - period)
    return math.copysign(min(v_max, magnitude), error)


class _Passes:
    """Counts how often an approach passes its goal. Passing it once and coming back is how a
    closed loop settles; passing it again on the way back is a swing that will not settle: the
    pose it steers on is predicted wrong (odometry later or earlier than the robot believes),
    and the approach stops to judge at rest and come back slowly."""

    def __init__(self) -> None:
        self.side = 0.0  # the sign of the error before the last pass (0: not yet known)
        self.count = 0

    def passed(self, error: float, tolerance: float) -> bool:
        """True once `error` (signed, along the approach) has crossed the goal twice by more
        than `tolerance`."""
        if self.side == 0.0:
            self.side = math.copysign(1.0, error)
        elif error * self.side <= -tolerance:
            self.side, self.count = -self.side, self.count + 1
        return self.count >= 2


def _arrived(error: float, speed: float, tolerance: float, period: float) -> bool:
    """Close enough, and commanded slow enough that stopping now keeps the robot within
    tolerance (whether it really stopped there is judged at rest, after `settle`)."""
    return abs(error) < tolerance and abs(speed) * period < tolerance


def drive_local(
    ctx: SkillContext, tx: float, ty: float, speed: float, relative: bool = False
) -> float:
    """Translate to (tx, ty) given in the body frame at the start, holding the heading.

    `relative`: the move is what a person asked ("walk forward 2 m"): when SLAM relocalizes
    the robot on the way (map -> odom jumps), the leg's start is carried over with it, so the
    robot still moves as asked; else the leg leads to a goal on the map and a jump stops it
    (Relocalized), so the caller plans again from the corrected pose.
    Returns the distance actually covered (measured).
    """
    robot = ctx.robot
    m = ctx.config.motion
    start = prev = ctx.state()
    origin = start.pose  # where the leg starts (carried over SLAM's jumps when relative)
    c, s = math.cos(origin.yaw), math.sin(origin.yaw)
    goal = math.hypot(tx, ty)
    ctx.begin_leg(start)
    margin = leg_margin(ctx.config.safety, goal)
    leg = (tx * c - ty * s, tx * s + ty * c)  # the planned leg, from its start
    axis = (leg[0] / goal, leg[1] / goal, 0.0) if goal else (1.0, 0.0, 0.0)  # its direction
    stopped_for_room = False  # the loop stopped for want of room and settled
    short = False  # ended short, within the outcome tolerance: the commands' room is used up
    for attempt in range(1 + _CORRECTIONS):
        best, best_time = math.inf, robot.now()  # each approach from rest gets its own time
        cap = speed if attempt == 0 else min(speed, m.position_tolerance / _CORRECTION_SECONDS)
        toward: tuple[float, float] | None = None  # where the goal lay when this approach began
        passes = _Passes()
        while True:
            st = ctx.state()
            if st.relocalized != prev.relocalized:
                if not relative:
                    _relocalized(ctx)
                origin = carried(origin, prev, st)
                c, s = math.cos(origin.yaw), math.sin(origin.yaw)
            prev = here = st
            dx, dy = here.x - origin.x, here.y - origin.y
            lx, ly = dx * c + dy * s, -dx * s + dy * c  # displacement in the start frame
            ex, ey = tx - lx, ty - ly
            error = math.hypot(ex, ey)
            told = math.hypot(*ctx.last_command[:2])  # the speed it was told: known at once
            if _arrived(error, told, m.position_tolerance, ctx.period):
                break
            if toward is None:
                toward = (ex / error, ey / error)
            if passes.passed(ex * toward[0] + ey * toward[1], m.position_tolerance):
                break  # it swings about the goal: judge at rest, then come back slowly
            if error < best - 1e-3:
                best, best_time = error, robot.now()
            elif robot.now() - best_time > m.stall_timeout:
                robot.stop()
                if st.blocked_by:
                    raise SkillError(f"blocked by {st.blocked_by} with {error:.2f} m to go")
                if error <= ctx.config.safety.outcome_tolerance:  # done, as steps are judged
                    ctx.notes.append(ended_short(f"{error:.2f} m", f"{goal:.2f} m leg", SLOW))
                    short = True
                    break
                raise SkillError(
                    f"no progress for {m.stall_timeout:.1f} s with {error:.2f} m to go: "
                    "the robot is blocked, stalled or ignoring velocity commands"
                )
            heading = origin.yaw + math.atan2(ey, ex)  # where the robot goes
            room, why = ctx.room(heading, error + 0.5, st)
            ox, oy, _ = ctx.commanded()
            # Going on along the leg, a robot whose speed-ups came late is short of its
            # commands by up to the leeway: they may go as much further as it lags (bounds.py).
            onward = math.cos(heading) * axis[0] + math.sin(heading) * axis[1] > 0
            lag = (ox - dx) * axis[0] + (oy - dy) * axis[1]  # odometry behind the commands
            back = ctx.leeway(axis).catch_up(lag, margin) if onward else 0.0
            left = leg_room((ox - axis[0] * back, oy - axis[1] * back), heading, leg, margin)
            by_commands = left < room
            if by_commands:
                room, why = left, disagree(math.hypot(ox, oy), goal, margin, goal - error, back)
            if room < m.position_tolerance and error >= m.position_tolerance:
                if not stopped_for_room:  # judge at rest: late odometry may only now catch up
                    stopped_for_room = True
                    settle(ctx)
                    best_time = robot.now()  # the wait at rest is no stall
                    continue
                if by_commands and error <= ctx.config.safety.outcome_tolerance:
                    ctx.notes.append(
                        ended_short(
                            f"{error:.2f} m",
                            f"{goal:.2f} m leg",
                            f"its commands had taken the robot {math.hypot(ox, oy):.2f} m, the "
                            f"most the leg allows, and odometry shows less ({LATE})",
                        )
                    )
                    short = True
                    break
                robot.stop()
                raise SkillError(f"stopped {error:.2f} m short of the goal: {why}")
            stopped_for_room = False
            # A command may be held (or act) as late as the stalls seen: brake that much sooner.
            v = abs(_profile(min(error, room), cap, m.linear_accel, ctx.period + ctx.stall()))
            yaw_error = normalize_angle(origin.yaw - here.yaw)
            # Body-frame command toward the goal; the start frame and the body differ by
            # yaw_error.
            bx, by = ex / error * v, ey / error * v
            cy, sy = math.cos(yaw_error), math.sin(yaw_error)
            ctx.drive(
                bx * cy - by * sy, bx * sy + by * cy, _profile(yaw_error, 0.5, 2.0, ctx.period)
            )
            ctx.on_progress(min(1.0, 1.0 - error / goal) if goal else 1.0)
            ctx.tick()
        settle(ctx)
        at_rest = ctx.state()
        if at_rest.relocalized != prev.relocalized:  # a jump while it settled
            if not relative:
                _relocalized(ctx)
            origin, prev = carried(origin, prev, at_rest), at_rest
            c, s = math.cos(origin.yaw), math.sin(origin.yaw)
        if short or _off(at_rest.pose, origin, tx, ty) < m.position_tolerance:
            break  # judged on the pose at rest, not on the one the loop stopped on
    end = ctx.state()
    if end.relocalized != prev.relocalized:
        origin = carried(origin, prev, end)
    leg_agrees(ctx, start, end, origin, margin, (tx, ty), ctx.leeway(axis))
    return math.hypot(end.x - origin.x, end.y - origin.y)


def rotate(ctx: SkillContext, angle: float, speed: float, relative: bool = False) -> float:
    """Turn in place by `angle` radians (+ counter-clockwise). `relative`: the turn is what a
    person asked, and a SLAM jump of the heading on the way is not counted as turning; else it
    faces a goal on the map and a jump stops it (Relocalized). Returns the measured turn."""
    robot = ctx.robot
    m = ctx.config.motion
    first = prev = ctx.state()
    last_yaw = first.yaw
    turned = 0.0
    ctx.begin_leg(first)
    margin = turn_margin(ctx.config.safety, angle)
    axis = (0.0, 0.0, math.copysign(1.0, angle))  # the way it turns
    stopped_for_room = False  # the loop stopped for want of room and settled
    short = False  # ended short, within the outcome tolerance: the commands' room is used up
    for attempt in range(1 + _CORRECTIONS):
        best, best_time = math.inf, robot.now()  # each approach from rest gets its own time
        cap = speed if attempt == 0 else min(speed, m.yaw_tolerance / _CORRECTION_SECONDS)
        passes = _Passes()
        while True:
            st = ctx.state()
            last_yaw, prev = _turn_jumped(ctx, last_yaw, prev, st, relative), st
            turned += normalize_angle(st.yaw - last_yaw)  # unwrapped, so 360 degree turns work
            last_yaw = st.yaw
            error = angle - turned
            if _arrived(error, ctx.last_command[2], m.yaw_tolerance, ctx.period):
                break
            if passes.passed(error, m.yaw_tolerance):
                break  # it swings about the goal: judge at rest, then come back slowly
            if abs(error) < best - 1e-3:
                best, best_time = abs(error), robot.now()
            elif robot.now() - best_time > m.stall_timeout:
                robot.stop()
                if abs(error) <= math.radians(ctx.config.safety.outcome_tolerance_deg):
                    done = f"{math.degrees(abs(error)):.1f} degrees"
                    ctx.notes.append(ended_short(done, f"{deg(angle)} degree turn", SLOW))
                    short = True
                    break
                raise SkillError(
                    f"no progress for {m.stall_timeout:.1f} s with {math.degrees(error):.0f} "
                    "degrees to go: the robot is blocked, stalled or ignoring velocity commands"
                )
            commanded = ctx.commanded()[2]
            # Going on the way it turns, a robot whose speed-ups came late is short of its
            # commands by up to the leeway: they may turn as much further as it lags (bounds.py).
            lag = axis[2] * (commanded - turned)  # odometry behind the commands
            back = ctx.leeway(axis).catch_up(lag, margin) if error * axis[2] > 0 else 0.0
            left = turn_room(commanded - axis[2] * back, error, angle, margin)
            if left < m.yaw_tolerance and abs(error) >= m.yaw_tolerance:
                if not stopped_for_room:  # judge at rest: late odometry may only now catch up
                    stopped_for_room = True
                    settle(ctx)
                    best_time = robot.now()  # the wait at rest is no stall
                    continue
                if abs(error) <= math.radians(ctx.config.safety.outcome_tolerance_deg):
                    ctx.notes.append(
                        ended_short(
                            f"{math.degrees(abs(error)):.1f} degrees",
                            f"{deg(angle)} degree turn",
                            f"its commands had turned the robot {deg(commanded)} degrees, the "
                            f"most the turn allows, and odometry shows less ({LATE})",
                        )
                    )
                    short = True
                    break
                robot.stop()
                raise SkillError(
                    f"stopped {math.degrees(abs(error)):.0f} degrees short of the turn: it was "
                    f"commanded {math.degrees(commanded):.0f} degrees for a "
                    f"{math.degrees(angle):.0f} degree turn (at most "
                    f"{math.degrees(margin):.0f} beyond it: safety.step_turn_margin_deg, "
                    f"step_travel_slack{allowing(ctx, math.degrees(back), 'degrees')}), yet "
                    "odometry does not show it turned: odometry disagrees with the motion (a "
                    "relocalization, a frozen stream?)"
                )
            stopped_for_room = False
            limit = math.copysign(min(abs(error), left), error)
            hold = ctx.period + ctx.stall()  # brake sooner by the stalls seen, as a leg does
            ctx.drive(0.0, 0.0, _profile(limit, cap, m.angular_accel, hold))
            ctx.on_progress(min(1.0, 1.0 - abs(error) / abs(angle)) if angle else 1.0)
            ctx.tick()
        settle(ctx)
        st = ctx.state()
        last_yaw, prev = _turn_jumped(ctx, last_yaw, prev, st, relative), st
        if short or abs(angle - turned - normalize_angle(st.yaw - last_yaw)) < m.yaw_tolerance:
            break  # judged on the heading at rest, not on the one the loop stopped on
    st = ctx.state()
    last_yaw = _turn_jumped(ctx, last_yaw, prev, st, relative)
    turned += normalize_angle(st.yaw - last_yaw)
    turn_agrees(ctx, turned, angle, margin, absorbed_yaw(first, st))
    return turned


def _turn_jumped(
    ctx: SkillContext, last_yaw: float, prev: RobotState, st: RobotState, relative: bool
) -> float:
    """The heading last seen, carried over a SLAM jump between `prev` and `st` (a relative
    turn); a turn toward a goal on the map stops on the jump instead (Relocalized)."""
    if st.relocalized == prev.relocalized:
        return last_yaw
    if not relative:
        _relocalized(ctx)
    return normalize_angle(last_yaw + st.jumps[2] - prev.jumps[2])


def _relocalized(ctx: SkillContext) -> None:
    """Stop a leg toward a goal on the map when localization has corrected the map pose on the
    way (SLAM's map -> odom jumped): its goal was set in the frame as it was, and walking on
    would take the robot as far wrong as the correction. Raises Relocalized once at rest."""
    ctx.robot.stop()
    settle(ctx)
    raise Relocalized(
        "localization corrected the robot's position on the map while it moved (SLAM's map -> "
        "odom jumped): stopped rather than go on toward a goal set before the correction"
    )


def _off(st: Pose2D, start: Pose2D, tx: float, ty: float) -> float:
    """How far `st` is from the goal (tx, ty), given in the body frame at `start`."""
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    dx, dy = st.x - start.x, st.y - start.y
    return math.hypot(tx - (dx * c + dy * s), ty - (-dx * s + dy * c))


def go_to(ctx: SkillContext, x: float, y: float, linear: float, angular: float) -> float:
    """Face the point (x, y) in the odom frame, then walk to it. Returns metres covered."""
    st = ctx.state()
    distance = math.hypot(x - st.x, y - st.y)
    if distance < ctx.config.motion.position_tolerance:
        return 0.0
    bearing = math.atan2(y - st.y, x - st.x)
    rotate(ctx, normalize_angle(bearing - st.yaw), angular)
    st = ctx.state()
    c, s = math.cos(st.yaw), math.sin(st.yaw)
    dx, dy = x - st.x, y - st.y
    return drive_local(ctx, dx * c + dy * s, -dx * s + dy * c, linear)


def follow(
    ctx: SkillContext,
    points: list[tuple[float, float]],
    linear: float,
    angular: float,
    done: float = 0.0,
) -> float:
    """Walk the straight legs through `points` (odom frame): at each, face the next point, then
    walk to it. Progress is the distance along the path (after `done` metres already walked
    of the route) over its whole length. Returns metres covered."""
    report = ctx.on_progress
    st = ctx.state()
    corners = [(st.x, st.y), *points]
    legs = [math.dist(a, b) for a, b in zip(corners, corners[1:], strict=False)]
    total = done + sum(legs)
    walked = 0.0

    def along(at: float) -> None:
        report(min(1.0, at / total) if total else 1.0)

    def from_here(at: float, leg: float) -> Callable[[float], None]:
        return lambda fraction: along(at + fraction * leg)

    try:
        for (x, y), leg in zip(points, legs, strict=True):
            st = ctx.state()
            if math.hypot(x - st.x, y - st.y) >= ctx.config.motion.position_tolerance:
                ctx.on_progress = from_here(done, 0.0)  # turning: no distance yet
                bearing = math.atan2(y - st.y, x - st.x)
                rotate(ctx, normalize_angle(bearing - st.yaw), angular)
                st = ctx.state()
                c, s = math.cos(st.yaw), math.sin(st.yaw)
                dx, dy = x - st.x, y - st.y
                ctx.on_progress = from_here(done, leg)
                walked += drive_local(ctx, dx * c + dy * s, -dx * s + dy * c, linear)
            done += leg
            along(done)
    finally:
        ctx.on_progress = report
    return walked


def settle(ctx: SkillContext) -> None:
    """Command zero and wait (bounded) until the robot has come to rest: on a robot whose
    odometry is late (a Go2), until odometry shows it at rest."""
    ctx.drive(0.0, 0.0, 0.0)
    for _ in range(int((_SETTLE_SECONDS + ctx.robot.latency) / ctx.period) + 1):
        st = ctx.state()
        if max(abs(st.vx), abs(st.vy), abs(st.wz)) < _SETTLE_SPEED:
            return
        ctx.tick()
