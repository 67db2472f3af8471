"""A leg or turn done, checked against its own commands, and the words that say how it ended.

Odometry that jumps by less than the robot could move between two samples is not seen as a
jump (robot/go2/odometry.py); it would end a leg or a turn early, reported as done. So at rest
the step compares where odometry puts the robot with where its commands alone put it (the
ledger, bounds.py): odometry *ahead* of the commands by more than the step's margin, beyond the
leeway of the stalls seen (commands that acted late on a loaded machine), fails. Commands
further along than odometry are what a link does (each command acts once it arrives, so a stop
that arrives sooner than the velocity before it cuts that short), and the commands' bound has
kept them within the margin, so the truth is within it too.
"""

from __future__ import annotations

import math

from ..errors import SkillError
from ..state import Pose2D, RobotState, normalize_angle
from .bounds import Leeway
from .context import SkillContext

LATE = "the robot slow to start, or commands late or lost on the way"
SLOW = "no progress for a while (the robot slow to follow: a loaded machine, a late link?)"


def leg_agrees(
    ctx: SkillContext,
    start: RobotState,
    end: RobotState,
    origin: Pose2D,
    margin: float,
    leg: tuple[float, float],
    leeway: Leeway,
) -> None:
    """A leg odometry says is done must agree with what its commands did: where odometry
    puts the robot (from the leg's start) and where the commands alone put it (the ledger,
    from the same start) may differ by at most the leg's margin, beyond the `leeway` of the
    stalls seen (commands that acted late: bounds.py). A jump of the odometry too small to be
    seen as one (within what the robot could move between two samples) otherwise ends the leg
    early by as much, reported as done.

    Where odometry puts the robot is read two ways, and the one nearer the commands counts:
    on the map (from `origin`, the leg's start carried over SLAM's jumps) and in odometry's
    own frame (`RobotState.own_pose`, from `start`). SLAM's corrections smaller than a jump
    move the map pose without the robot moving (one that came in mid-leg on a loaded machine
    failed an honest leg), and odometry's own pose drifts (which the map corrects): neither is
    a lie. A small jump of odometry shows in both (the map pose is odometry's, corrected).

    Only odometry *ahead* of the commands along the leg (`leg`: its goal, in the start's body
    frame) counts: commands further along than odometry are what a link does (each command
    acts once it arrives, so a stop that arrives sooner than the velocity before it cuts that
    short), and leg_room has kept them within the margin, so the truth is within it too."""
    ox, oy, _ = ctx.commanded()  # in the world frame the leg began in, from start.pose
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    commanded = (ox * c + oy * s, -ox * s + oy * c)
    length = math.hypot(*leg)

    def apart(first: Pose2D, last: Pose2D) -> tuple[float, float]:
        """(how far ahead of the commands, beyond the leeway; metres measured) from `first`
        to `last`, in the frame of `first`."""
        c, s = math.cos(first.yaw), math.sin(first.yaw)
        dx, dy = last.x - first.x, last.y - first.y
        mx, my = dx * c + dy * s, -dx * s + dy * c
        ax, ay = mx - commanded[0], my - commanded[1]
        if length > 0:
            ux, uy = leg[0] / length, leg[1] / length
            along, aside = ax * ux + ay * uy, abs(ax * uy - ay * ux)
        else:
            along, aside = math.hypot(ax, ay), 0.0
        # Ahead, and to either side, beyond what the stalls seen explain.
        off = math.hypot(max(0.0, along - leeway.ahead), max(0.0, aside - leeway.aside))
        return off, math.hypot(mx, my)

    gap, measured = min(apart(origin, end.pose), apart(start.own_pose, end.own_pose))
    if gap > margin:
        ctx.robot.stop()
        raise SkillError(
            f"odometry shows the leg done ({measured:.2f} m), yet its commands "
            f"took the robot {math.hypot(*commanded):.2f} m, {gap:.2f} m apart (at most "
            f"{margin:.2f}: safety.step_travel_margin, step_travel_slack"
            f"{allowing(ctx, leeway.ahead, 'm')}): odometry disagrees with the motion (a "
            "small jump, a slipping or lifted robot?)"
        )


def turn_agrees(
    ctx: SkillContext, turned: float, angle: float, margin: float, absorbed: float = 0.0
) -> None:
    """A turn odometry says is done (`turned` of `angle`, radians, on the map, SLAM's jumps
    carried) must agree with what its commands turned: odometry further than they could have
    (a heading jump too small to be seen as one), by more than `margin` and the leeway of the
    stalls seen, fails. As for a leg, the heading nearer the commands counts: the map's, or
    odometry's own (`absorbed`, what SLAM's corrections smaller than a jump turned the map by,
    taken off: `absorbed_yaw`)."""
    commanded = ctx.commanded()[2]
    way = math.copysign(1.0, angle)

    def ahead(measured: float) -> float:  # ahead counts
        return way * (measured - commanded) if angle else abs(measured - commanded)

    turned = min((turned, turned - absorbed), key=ahead)
    apart = ahead(turned)
    lead = ctx.leeway((0.0, 0.0, way)).ahead  # late slowings
    if apart > margin + lead:
        ctx.robot.stop()
        raise SkillError(
            f"odometry shows the turn done ({math.degrees(turned):.0f} degrees), yet its "
            f"commands turned the robot {math.degrees(commanded):.0f} degrees (at most "
            f"{math.degrees(margin):.0f} apart: safety.step_turn_margin_deg, step_travel_slack"
            f"{allowing(ctx, math.degrees(lead), 'degrees')}): odometry disagrees with the "
            "motion (a small jump of the heading?)"
        )


def absorbed_yaw(first: RobotState, end: RobotState) -> float:
    """Radians SLAM's corrections smaller than a jump turned the map heading between `first`
    and `end` (it moved without the robot turning): the map -> odom change in yaw, less the
    jumps' (a turn carries those over itself, or stops on them). What a turn's check against
    its commands takes off the heading the map shows."""
    total = (end.yaw - end.own_pose.yaw) - (first.yaw - first.own_pose.yaw)
    return normalize_angle(total - (end.jumps[2] - first.jumps[2]))


def ended_short(short: str, planned: str, why: str) -> str:
    """The note of a leg or turn that ended `short` of the `planned` one, within the step's
    outcome tolerance, and `why` it ended there."""
    return f"ended {short} short of the {planned}: {why}"


def deg(radians: float) -> str:
    return f"{math.degrees(abs(radians)):.0f}"


def allowing(ctx: SkillContext, extra: float, unit: str) -> str:
    """What a limit allowed beyond its margin for the stalls seen ('' when none were)."""
    if extra <= 0.0:
        return ""
    spec = ".2f" if unit == "m" else ".0f"
    return f", and {extra:{spec}} {unit} more for {ctx.stall():.2f} s of stalls seen"


def disagree(commanded: float, goal: float, margin: float, measured: float, extra: float) -> str:
    """Why a leg stopped when its commands would take the robot off the planned leg (by
    `margin`, and `extra` for the stalls seen): odometry shows it short of the goal (or
    nowhere near)."""
    more = f", and {extra:.2f} m more for the stalls seen" if extra > 0 else ""
    lead = (
        f"its commands took it {commanded:.2f} m for a {goal:.2f} m leg (at most {margin:.2f} "
        f"m off the leg: safety.step_travel_margin, step_travel_slack{more}), yet odometry "
        f"shows {measured:.2f} m"
    )
    if measured < 0.25 * commanded:
        return (
            f"{lead}: the commands do not reach the robot or it ignores them (is it "
            "standing? does another controller hold it?), or odometry is frozen"
        )
    return f"{lead}: odometry disagrees with the motion (a relocalization, a frozen stream?)"
