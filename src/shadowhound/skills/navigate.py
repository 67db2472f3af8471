"""nav.goto through the robot's navigator (Nav2's NavigateToPose), chosen by the `navigation`
setting: auto uses it when it answers, else the project's own planner; nav2 requires it; direct
never uses it.

A goal in flight is followed in the control loop: its feedback (distance remaining) is the
step's progress; cancellation, the skill's time-out, a stop or an e-stop cancel the goal (the
robot's `stop` cancels its navigator's goals too, from any thread). Nav2 stops within its own
goal tolerance (0.25 m by default); the last centimetres and the heading are closed by the
project's controller, so the step ends where the plan said, within the outcome tolerance.

Nav2 drives at its own controller's speeds, which the governor cannot cap: the walk measures
the robot's speed over each second and cancels the goal when it exceeds
`safety.max_linear_speed` by more than SPEED_SLACK. The speed is what the robot's odometer
counted (`distance_travelled`: odometry's consistent steps, in its own frame), not how far its
map pose moved, which SLAM's map -> odom corrections move without the robot moving (a flapping
one looked like 0.78 m/s while the robot walked at 0.40: issue 32). It is the lesser of two
measures, each of which one honest hitch inflates: the count over the last second (a late
burst of odometry crowds more than a second's steps into it) and over the time the samples
themselves say the robot moved (`time_moving`, on their stamps: a shift of the stamps' clock
offset shortens it; a stall seen in the window, `Robot.stalls`, held the odometry up and the
clock's measure allows for it). A Nav2 that drives too fast shows in both.
"""

from __future__ import annotations

import math
from collections import deque

from ..errors import SkillError
from ..robot.base import MAX_STALL
from ..robot.navigator import Navigator, NavStatus
from ..state import normalize_angle
from . import motion
from .context import SkillContext

# Seconds nav.goto waits for the navigator's server to answer: briefly under `auto` (it falls
# back at once when there is none), longer when Nav2 is required.
AUTO_WAIT = 1.0
REQUIRED_WAIT = 5.0
ACCEPT_WAIT = 5.0  # seconds a sent goal may wait to be accepted or rejected
SPEED_WINDOW = 1.0  # seconds of odometry the measured speed is averaged over
SPEED_SLACK = 1.25  # measured speed may exceed the limit by this factor (odometry noise)


def choose(ctx: SkillContext) -> Navigator | None:
    """The navigator nav.goto should use here, or None for the project's own planner. Raises
    SkillError when `navigation: nav2` and there is none, naming what to do."""
    mode = ctx.config.navigation
    if mode == "direct":
        return None
    navigator = ctx.robot.navigator()
    if navigator is None:
        if mode == "nav2":
            raise SkillError(
                f"navigation is 'nav2', but the robot {ctx.robot.name!r} has no "
                "Nav2 navigator (only a Go2 on ROS 2 has one); set navigation: "
                "auto or direct"
            )
        return None
    if navigator.ready(REQUIRED_WAIT if mode == "nav2" else AUTO_WAIT):
        return navigator
    if mode == "nav2":
        raise SkillError(
            f"navigation is 'nav2', but {navigator.name} did not answer in "
            f"{REQUIRED_WAIT:g} s: launch Nav2 (docs/go2-nav2.md), or set "
            "navigation: auto (the project's own planner when Nav2 is absent) "
            "or direct"
        )
    ctx.notes.append(f"{navigator.name} did not answer: walked the project's own path")
    return None


def navigate(
    ctx: SkillContext,
    navigator: Navigator,
    goal: tuple[float, float],
    yaw: float,
    linear: float,
    angular: float,
) -> float:
    """Walk to `goal` (facing `yaw` at the end) through `navigator`. Returns metres covered.
    Raises SkillError in words when the navigator fails or cancels the goal itself."""
    before = ctx.robot.get_state().distance_travelled
    handle = navigator.navigate(goal[0], goal[1], yaw)
    sent = ctx.robot.now()
    first: float | None = None
    recoveries = 0
    odometer: deque[tuple[float, float, float]] = deque()
    try:
        while True:
            _check_speed(ctx, navigator.name, odometer)
            report = handle.report()
            fb = report.feedback
            if fb is not None:
                recoveries = fb.recoveries
                if first is None and fb.distance_remaining > 0:
                    first = fb.distance_remaining
                if first:
                    ctx.on_progress(max(0.0, min(1.0, 1.0 - fb.distance_remaining / first)))
            if report.status is NavStatus.PENDING and ctx.robot.now() - sent > ACCEPT_WAIT:
                raise SkillError(
                    f"{navigator.name} did not accept or reject the goal in {ACCEPT_WAIT:g} s"
                )
            if report.status is NavStatus.SUCCEEDED:
                break
            if report.status is NavStatus.FAILED:
                raise SkillError(f"{navigator.name}: {report.message}")
            if report.status is NavStatus.CANCELED:
                raise SkillError(
                    f"{navigator.name} cancelled the goal"
                    + (f": {report.message}" if report.message else "")
                )
            ctx.tick()  # raises on cancel, e-stop (cancelled) and time-out
    except BaseException:
        handle.cancel()
        raise
    if recoveries:
        ctx.notes.append(
            f"{navigator.name} ran {recoveries} recovery behaviour"
            + ("s" if recoveries != 1 else "")
        )
    ctx.robot.stop()  # Nav2's last zero Twist is dropped by go2_ros2_sdk: StopMove ends it
    motion.settle(ctx)
    _finish(ctx, goal, yaw, linear, angular)
    return ctx.robot.get_state().distance_travelled - before


def _check_speed(ctx: SkillContext, name: str, odometer: deque[tuple[float, float, float]]) -> None:
    """Raise SkillError when the robot's odometer counted more than the safety limit allows
    over the last SPEED_WINDOW seconds, by the clock and by the time it counted moving."""
    st = ctx.robot.get_state()
    now = ctx.robot.now()
    odometer.append((now, st.distance_travelled, st.time_moving))
    while len(odometer) > 2 and now - odometer[1][0] >= SPEED_WINDOW:
        odometer.popleft()
    t0, d0, moving0 = odometer[0]
    if now - t0 < SPEED_WINDOW:
        return
    counted, moving = st.distance_travelled - d0, st.time_moving - moving0
    # Odometry held up by a stall seen in the window (a loaded machine, a late link) comes in
    # at once: by the clock, what it counts took that much longer.
    held = min(MAX_STALL, max((s.seconds for s in ctx.robot.stalls(t0)), default=0.0))
    speed = min(counted / (now - t0 + held), counted / moving if moving > 0 else math.inf)
    limit = ctx.config.safety.max_linear_speed
    if speed > limit * SPEED_SLACK:
        raise SkillError(
            f"{name} drove at {speed:.2f} m/s, above the {limit:g} m/s limit "
            "(safety.max_linear_speed): goal cancelled; lower Nav2's controller "
            "speed to the limit"
        )


def _finish(
    ctx: SkillContext, goal: tuple[float, float], yaw: float, linear: float, angular: float
) -> None:
    """Close what Nav2's goal tolerance left: a short straight step (sideways if need be, no
    turn first), then the heading."""
    st = ctx.robot.get_state()
    dx, dy = goal[0] - st.x, goal[1] - st.y
    if math.hypot(dx, dy) >= ctx.config.motion.position_tolerance:
        c, s = math.cos(st.yaw), math.sin(st.yaw)
        motion.drive_local(ctx, dx * c + dy * s, -dx * s + dy * c, linear)
    turn = normalize_angle(yaw - ctx.robot.get_state().yaw)
    if abs(turn) >= ctx.config.motion.yaw_tolerance:
        motion.rotate(ctx, turn, angular)
